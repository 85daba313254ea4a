// Internal: the per-cube step of marching cubes, shared by the grid contourer and the Poisson
// extractor. Inside is value < 0.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// Cube corners are numbered by bits (x=1, y=2, z=4). A cube edge is (its corner with the axis bit
// clear, axis); local edge id = axis * 4 + rank of that corner among the four.
struct CubeTables {
  int edge_id[8][3];        // edge_id[low corner][axis], -1 if the corner has that bit set
  int edge_low_corner[12];  // the inverse: edge id -> its low corner (the axis is id / 4)
  // For each of the 6 faces (axis a, side s): its 4 corners counter-clockwise seen from outside.
  int face_corner[6][4];
  int edge_faces[12];  // bit (axis * 2 + side) for each of the two faces an edge lies on
  CubeTables();
  int edge_between(int c0, int c1) const {
    const int diff = c0 ^ c1;
    const int axis = diff == 1 ? 0 : diff == 2 ? 1 : 2;
    return edge_id[std::min(c0, c1)][axis];
  }
};

const CubeTables& cube_tables();

/// What a cube's polygons depend on: which corners are inside (bit c for corner c, value < 0) and,
/// for each face with two diagonal pairs of equal sign, whether its inside corners connect (bit
/// f for face f = 2 axis + side). Two bytes where the corner values take 64.
struct CubeCase {
  std::uint8_t inside = 0;
  std::uint8_t insides_connected = 0;
  bool mixed() const { return inside != 0 && inside != 0xff; }
};

/// The case of a cube with these corner values. An ambiguous face is resolved by the asymptotic
/// decider on its bilinear interpolant, evaluated in the face's own corner order so that both
/// cubes sharing it decide alike.
inline CubeCase cube_case(const double value[8]) {
  const CubeTables& T = cube_tables();
  CubeCase out;
  for (int c = 0; c < 8; ++c) out.inside |= std::uint8_t((value[c] < 0) << c);
  for (int face = 0; face < 6; ++face) {
    const int* c = T.face_corner[face];
    const bool i0 = value[c[0]] < 0, i1 = value[c[1]] < 0, i2 = value[c[2]] < 0,
               i3 = value[c[3]] < 0;
    if (!(i0 == i2 && i1 == i3 && i0 != i1)) continue;  // not two diagonal pairs
    const int a = face / 2, u = (a + 1) % 3, v = (a + 2) % 3, side = (face & 1) << a;
    const double f00 = value[side], f10 = value[side | 1 << u], f11 = value[side | 1 << u | 1 << v],
                 f01 = value[side | 1 << v];
    const double saddle = (f00 * f11 - f10 * f01) / (f00 + f11 - f10 - f01);
    out.insides_connected |= std::uint8_t((saddle < 0) << face);
  }
  return out;
}

/// Traces the polygons of a cube of this case around its faces. For each polygon, calls
/// emit(edges, size) with its vertices as local edge ids, ordered counter-clockwise seen from
/// outside (value >= 0).
template <class Emit>
void cube_polygons(CubeCase cube, Emit&& emit) {
  const CubeTables& T = cube_tables();
  auto inside = [&](int corner) { return (cube.inside >> corner & 1) != 0; };
  int next_edge[12];  // the edge where the segment starting at edge e's crossing ends
  std::fill(std::begin(next_edge), std::end(next_edge), -1);
  for (int face = 0; face < 6; ++face) {
    const int* c = T.face_corner[face];
    int starts[2], ends[2], ns = 0, ne = 0, order[4], crossings = 0;
    for (int q = 0; q < 4; ++q) {
      const int c0 = c[q], c1 = c[(q + 1) % 4];
      if (inside(c0) == inside(c1)) continue;
      order[crossings++] = T.edge_between(c0, c1);
      if (inside(c1))
        starts[ns++] = crossings - 1;  // outside -> inside
      else
        ends[ne++] = crossings - 1;
    }
    if (crossings == 2) {
      next_edge[order[starts[0]]] = order[ends[0]];
    } else if (crossings == 4) {
      const bool insides_connected = (cube.insides_connected >> face & 1) != 0;
      for (int s = 0; s < 2; ++s) {
        const int at = starts[s];
        next_edge[order[at]] = order[insides_connected ? (at + 3) % 4 : (at + 1) % 4];
      }
    }
  }
  bool visited[12] = {};
  for (int e0 = 0; e0 < 12; ++e0) {
    if (next_edge[e0] < 0 || visited[e0]) continue;
    int edges[12], size = 0;
    for (int e = e0; !visited[e]; e = next_edge[e]) {
      visited[e] = true;
      edges[size++] = e;
    }
    emit(static_cast<const int*>(edges), size);
  }
}

/// The same from the cube's corner values.
template <class Emit>
void cube_polygons(const double value[8], Emit&& emit) {
  cube_polygons(cube_case(value), std::forward<Emit>(emit));
}

/// Triangles whose vertex id -k-1 names the k-th centroid vertex.
struct PolygonOutput {
  std::vector<std::array<int, 3>> triangles;
  std::vector<Eigen::Vector3d> centroids;
};

/// Triangulates a cube's polygon (vertex ids, the cube edges they lie on, their positions) as a
/// fan. A fan diagonal must not join two vertices on one cube face: the neighbouring cube could
/// use the same chord, and the mesh would stop being manifold there. Among the apexes whose
/// diagonals avoid that, the one with the shortest diagonals (sum of squares) wins; if there is
/// none, the fan starts from a new vertex at the polygon's centroid.
void triangulate_polygon(const int* polygon, const int* edges, const Eigen::Vector3d* position,
                         int size, PolygonOutput& out);

/// Completes a mesh whose vertices so far are the edge vertices: appends the parts' centroid
/// vertices in part order and sets the triangles (the parts' triangles in order, centroid ids
/// resolved).
void polygons_to_mesh(const std::vector<PolygonOutput>& parts, Mesh& mesh);

}  // namespace sdfcontour::detail
