// libFuzzer target: arbitrary small meshes through what `sample` does with a mesh: the checks
// (closed, oriented, coordinates), the union of overlapping parts, the winding-number signed
// distance and a small grid of it. Coordinates come from a coarse lattice, so that coincident
// vertices, zero-area and coplanar triangles and parts that cross are common. Any exception other
// than Error, a crash or a non-finite sample is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_union.h"
#include "sdfcontour/input/signed_distance.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sdfcontour;
  if (size < 2) return 0;
  const int vertices = 3 + data[0] % 14, triangles = 1 + data[1] % 24;
  if (size < std::size_t(2 + 3 * vertices + 3 * triangles)) return 0;
  Mesh mesh;
  mesh.vertices.resize(vertices, 3);
  const std::uint8_t* at = data + 2;
  for (int v = 0; v < vertices; ++v)
    for (int a = 0; a < 3; ++a) mesh.vertices(v, a) = (int(*at++ % 9) - 4) / 5.0;
  mesh.triangles.resize(triangles, 3);
  for (int t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) mesh.triangles(t, k) = *at++ % vertices;
  try {
    require_closed_mesh(mesh, "the mesh");
    const MeshSdf sdf(union_of_overlapping_parts(mesh));
    const Grid grid = sample_grid(sdf, 5, Bounds{});
    for (Eigen::Index i = 0; i < grid.values.size(); ++i)
      if (!std::isfinite(grid.values[i])) __builtin_trap();
  } catch (const Error&) {
  }
  return 0;
}
