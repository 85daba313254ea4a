#include "sdfcontour/reconstruction/subdivision.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace sdfcontour {

namespace {

std::uint64_t edge_key(int a, int b) {
  return std::uint64_t(std::uint32_t(std::min(a, b))) << 32 | std::uint32_t(std::max(a, b));
}

}  // namespace

Mesh midpoint_subdivision(const Mesh& mesh) {
  const Eigen::Index f = mesh.triangles.rows(), n = mesh.vertices.rows();
  std::vector<std::uint64_t> edges(std::size_t(3 * f));
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    for (int k = 0; k < 3; ++k)
      edges[std::size_t(3 * t + k)] =
          edge_key(mesh.triangles(t, k), mesh.triangles(t, (k + 1) % 3));
  });
  tbb::parallel_sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Mesh out;
  out.vertices.resize(n + Eigen::Index(edges.size()), 3);
  out.vertices.topRows(n) = mesh.vertices;
  tbb::parallel_for(std::size_t(0), edges.size(), [&](std::size_t e) {
    const int a = int(edges[e] >> 32), b = int(edges[e] & 0xffffffffu);
    out.vertices.row(n + Eigen::Index(e)) = 0.5 * (mesh.vertices.row(a) + mesh.vertices.row(b));
  });
  auto middle = [&](int a, int b) {
    return int(n + (std::lower_bound(edges.begin(), edges.end(), edge_key(a, b)) - edges.begin()));
  };
  out.triangles.resize(4 * f, 3);
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    const int a = mesh.triangles(t, 0), b = mesh.triangles(t, 1), c = mesh.triangles(t, 2);
    const int ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
    out.triangles.row(4 * t) << a, ab, ca;
    out.triangles.row(4 * t + 1) << ab, b, bc;
    out.triangles.row(4 * t + 2) << ca, bc, c;
    out.triangles.row(4 * t + 3) << ab, bc, ca;
  });
  return out;
}

}  // namespace sdfcontour
