#include "sdfcontour/extraction/marching.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "extraction/cube_polygons.h"

namespace sdfcontour {

namespace {

Eigen::Vector3d row(const PointMatrix& m, Eigen::Index i) {
  return m.row(i).transpose();
}

// Crossing point on the segment from a (value fa) to b (value fb), fa and fb of opposite sign.
Eigen::Vector3d crossing(const Eigen::Vector3d& a, double fa, const Eigen::Vector3d& b, double fb) {
  const double t = fa / (fa - fb);
  return a + t * (b - a);
}

bool inside(double v) {
  return v < 0;
}

std::uint64_t edge_key(int a, int b) {
  return (std::uint64_t(std::min(a, b)) << 32) | std::uint64_t(std::max(a, b));
}

// Parity of a permutation of 4 distinct values (true if odd).
bool odd_permutation(const std::array<int, 4>& p) {
  int inversions = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) inversions += p[std::size_t(i)] > p[std::size_t(j)];
  return inversions & 1;
}

}  // namespace

Mesh marching_tetrahedra(const PointMatrix& points, const Eigen::VectorXd& values,
                         const TetMatrix& tets) {
  const Eigen::Index m = tets.rows();
  // 1. One vertex per sign-changing edge, numbered in sorted edge order.
  std::vector<std::uint64_t> edges;
  for (Eigen::Index t = 0; t < m; ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (inside(values[tets(t, a)]) != inside(values[tets(t, b)]))
          edges.push_back(edge_key(tets(t, a), tets(t, b)));
  tbb::parallel_sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Mesh mesh;
  mesh.vertices.resize(Eigen::Index(edges.size()), 3);
  tbb::parallel_for(std::size_t(0), edges.size(), [&](std::size_t e) {
    const int a = int(edges[e] >> 32), b = int(edges[e] & 0xffffffffu);
    mesh.vertices.row(Eigen::Index(e)) =
        crossing(row(points, a), values[a], row(points, b), values[b]).transpose();
  });
  auto vertex_of = [&](int a, int b) {
    return int(std::lower_bound(edges.begin(), edges.end(), edge_key(a, b)) - edges.begin());
  };

  // 2. Up to two triangles per tet, written at offsets from a prefix sum so the order is fixed.
  std::vector<int> count(std::size_t(m) + 1, 0);
  for (Eigen::Index t = 0; t < m; ++t) {
    int negatives = 0;
    for (int k = 0; k < 4; ++k) negatives += inside(values[tets(t, k)]);
    count[std::size_t(t) + 1] = negatives == 2 ? 2 : (negatives == 1 || negatives == 3) ? 1 : 0;
  }
  for (Eigen::Index t = 0; t < m; ++t) count[std::size_t(t) + 1] += count[std::size_t(t)];
  mesh.triangles.resize(count.back(), 3);
  tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index t) {
    int at = count[std::size_t(t)];
    if (count[std::size_t(t) + 1] == at) return;
    std::array<int, 4> v{tets(t, 0), tets(t, 1), tets(t, 2), tets(t, 3)};
    std::array<int, 4> neg{}, pos{};
    int nn = 0, np = 0;
    for (int k = 0; k < 4; ++k)
      (inside(values[v[std::size_t(k)]]) ? neg[std::size_t(nn++)] : pos[std::size_t(np++)]) = k;
    // Reorder the tet by an even permutation (orientation kept) and emit faces that point from
    // the inside vertices towards the outside ones.
    if (nn == 2) {
      std::array<int, 4> perm{neg[0], neg[1], pos[0], pos[1]};
      if (odd_permutation(perm)) std::swap(perm[2], perm[3]);
      const int a0 = v[std::size_t(perm[0])], a1 = v[std::size_t(perm[1])],
                b0 = v[std::size_t(perm[2])], b1 = v[std::size_t(perm[3])];
      const int q[4] = {vertex_of(a0, b0), vertex_of(a0, b1), vertex_of(a1, b1), vertex_of(a1, b0)};
      // Split along the shorter diagonal.
      const double d02 = (mesh.vertices.row(q[0]) - mesh.vertices.row(q[2])).squaredNorm();
      const double d13 = (mesh.vertices.row(q[1]) - mesh.vertices.row(q[3])).squaredNorm();
      if (d02 <= d13) {
        mesh.triangles.row(at++) << q[0], q[1], q[2];
        mesh.triangles.row(at++) << q[0], q[2], q[3];
      } else {
        mesh.triangles.row(at++) << q[1], q[2], q[3];
        mesh.triangles.row(at++) << q[1], q[3], q[0];
      }
      return;
    }
    const bool lone_inside = nn == 1;
    const int k = lone_inside ? neg[0] : pos[0];
    std::array<int, 4> perm{k, 0, 0, 0};
    for (int o = 0, s = 1; o < 4; ++o)
      if (o != k) perm[std::size_t(s++)] = o;
    if (odd_permutation(perm)) std::swap(perm[2], perm[3]);
    const int apex = v[std::size_t(perm[0])];
    int e1 = vertex_of(apex, v[std::size_t(perm[1])]),
        e2 = vertex_of(apex, v[std::size_t(perm[2])]),
        e3 = vertex_of(apex, v[std::size_t(perm[3])]);
    // (e1, e2, e3) faces away from the apex: right when the apex is the lone inside vertex.
    if (!lone_inside) std::swap(e2, e3);
    mesh.triangles.row(at) << e1, e2, e3;
  });
  return mesh;
}

namespace {

// Marching cubes with O(nx * ny) bookkeeping instead of a map over every grid point. A grid
// "line" is (i, j) with k varying; the vertices on a line's sign-changing edges of one axis are
// numbered consecutively in k, lines and axes in C order, so a cube finds an edge's vertex from
// the line's first id plus the number of crossings before it on the line, counted as the cube
// sweeps along k.
template <class Value>
class CubeMarcher {
 public:
  explicit CubeMarcher(const GridView& grid)
      : g_(grid),
        f_(static_cast<const Value*>(grid.data)),
        nx_(grid.dims[0]),
        ny_(grid.dims[1]),
        nz_(grid.dims[2]),
        h_(grid.spacing()) {}

  Mesh run() {
    number_vertices();
    Mesh mesh;
    mesh.vertices.resize(line_base_.back(), 3);
    tbb::parallel_for(0, nx_, [&](int i) { place_vertices(i, mesh.vertices); });
    std::vector<detail::PolygonOutput> slabs(std::size_t(std::max(nx_ - 1, 0)));
    tbb::parallel_for(0, nx_ - 1,
                      [&](int i) { march_slab(i, mesh.vertices, slabs[std::size_t(i)]); });
    detail::polygons_to_mesh(slabs, mesh);
    return mesh;
  }

 private:
  bool inside(std::size_t p) const { return f_[p] < 0; }
  // Whether the edge from grid point p along `axis` changes sign (and exists).
  bool crosses(int i, int j, int k, int axis) const {
    const int reach[3] = {i + 1 < nx_, j + 1 < ny_, k + 1 < nz_};
    if (!reach[axis]) return false;
    const std::size_t p = g_.index(i, j, k), q = p + stride(axis);
    return inside(p) != inside(q);
  }
  std::size_t stride(int axis) const {
    return axis == 0 ? std::size_t(ny_) * nz_ : axis == 1 ? std::size_t(nz_) : 1;
  }
  std::size_t line(int i, int j) const { return std::size_t(i) * ny_ + j; }

  // line_base_[3 * line + axis]: the first vertex id on that line and axis. The one full pass
  // over the grid: the later passes visit only lines and cube rows with a crossing.
  void number_vertices() {
    line_base_.assign(std::size_t(nx_) * ny_ * 3 + 1, 0);
    tbb::parallel_for(0, nx_, [&](int i) {
      for (int j = 0; j < ny_; ++j) {
        const Value* f = f_ + g_.index(i, j, 0);
        const Value* next[2] = {i + 1 < nx_ ? f + stride(0) : nullptr,
                                j + 1 < ny_ ? f + stride(1) : nullptr};
        long* count = &line_base_[3 * line(i, j) + 1];
        for (int a = 0; a < 2; ++a) {
          if (!next[a]) continue;
          long c = 0;
          for (int k = 0; k < nz_; ++k) c += (f[k] < 0) != (next[a][k] < 0);
          count[a] = c;
        }
        long c = 0;
        for (int k = 0; k + 1 < nz_; ++k) c += (f[k] < 0) != (f[k + 1] < 0);
        count[2] = c;
      }
    });
    for (std::size_t e = 1; e < line_base_.size(); ++e) line_base_[e] += line_base_[e - 1];
  }
  long crossings(int i, int j, int axis) const {
    const std::size_t e = 3 * line(i, j) + std::size_t(axis);
    return line_base_[e + 1] - line_base_[e];
  }

  void place_vertices(int i, PointMatrix& vertices) const {
    for (int j = 0; j < ny_; ++j)
      for (int a = 0; a < 3; ++a) {
        if (crossings(i, j, a) == 0) continue;
        Eigen::Index next = line_base_[3 * line(i, j) + std::size_t(a)];
        for (int k = 0; k < nz_; ++k) {
          if (!crosses(i, j, k, a)) continue;
          const std::size_t p = g_.index(i, j, k);
          const double fa = f_[p], fb = f_[p + stride(a)];
          Eigen::Vector3d x = g_.point(i, j, k);
          x[a] += fa / (fa - fb) * h_[a];
          vertices.row(next++) = x.transpose();
        }
      }
  }

  void march_slab(int i, const PointMatrix& vertices, detail::PolygonOutput& out) const {
    const detail::CubeTables& T = detail::cube_tables();
    for (int j = 0; j + 1 < ny_; ++j) {
      // Every edge of this row of cubes is on a line counted above: no crossing, no polygon.
      if (crossings(i, j, 0) + crossings(i, j, 1) + crossings(i, j, 2) + crossings(i + 1, j, 1) +
              crossings(i + 1, j, 2) + crossings(i, j + 1, 0) + crossings(i, j + 1, 2) +
              crossings(i + 1, j + 1, 2) ==
          0)
        continue;
      // rank[corner line][axis]: crossings before the current k on that line and axis.
      long rank[4][3] = {};
      for (int k = 0; k + 1 < nz_; ++k) {
        double value[8];
        int mask = 0;
        for (int c = 0; c < 8; ++c) {
          value[c] = f_[g_.index(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))];
          mask |= (value[c] < 0) << c;
        }
        if (mask == 0 || mask == 255) continue;  // no crossing: every rank stays
        detail::cube_polygons(value, [&](const int* edges, int size) {
          int polygon[12];
          Eigen::Vector3d position[12];
          for (int q = 0; q < size; ++q) {
            const int c = T.edge_low_corner[edges[q]], a = edges[q] / 4, l = c & 3;
            const long base = line_base_[3 * line(i + (c & 1), j + (c >> 1 & 1)) + std::size_t(a)];
            // An edge at k + 1 has the line's edge at k before it, if that one crosses.
            const long before = rank[l][a] + ((c & 4) ? crossing_at_k(value, l, a) : 0);
            polygon[q] = int(base + before);
            position[q] = vertices.row(polygon[q]).transpose();
          }
          detail::triangulate_polygon(polygon, edges, position, size, out);
        });
        // Advance the ranks past this k.
        for (int l = 0; l < 4; ++l)
          for (int a = 0; a < 3; ++a) rank[l][a] += crossing_at_k(value, l, a);
      }
    }
  }

  // Whether the edge of `axis` from corner `l` (at this k, z bit clear) crosses, in this cube's
  // values. Edges that leave the cube (the axis bit already set in l) are never asked for.
  static int crossing_at_k(const double value[8], int l, int axis) {
    const int bit = 1 << axis;
    if (l & bit) return 0;
    return (value[l] < 0) != (value[l | bit] < 0);
  }

  const GridView& g_;
  const Value* f_;
  int nx_, ny_, nz_;
  Eigen::Vector3d h_;
  std::vector<long> line_base_;
};

}  // namespace

Mesh marching_cubes(const GridView& grid) {
  if (grid.type == ScalarType::Float32) return CubeMarcher<float>(grid).run();
  return CubeMarcher<double>(grid).run();
}

Mesh marching_cubes(const Grid& grid) {
  return marching_cubes(view_of(grid));
}

}  // namespace sdfcontour
