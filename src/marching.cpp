#include "sdfcontour/marching.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "cube_polygons.h"

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

Mesh marching_cubes(const Grid& grid) {
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const detail::CubeTables& T = detail::cube_tables();
  const auto& f = grid.values;
  // 1. A vertex on every sign-changing grid edge: vertex_id[3 * point + axis].
  std::vector<int> vertex_id(grid.size() * 3, -1);
  std::vector<int> slab_count(std::size_t(nx) + 1, 0);
  auto for_edges_in_slab = [&](int i, auto&& visit) {
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const std::size_t p = grid.index(i, j, k);
        const int step[3] = {i + 1 < nx, j + 1 < ny, k + 1 < nz};
        const std::size_t q[3] = {p + std::size_t(ny) * nz, p + std::size_t(nz), p + 1};
        for (int a = 0; a < 3; ++a)
          if (step[a] && inside(f[Eigen::Index(p)]) != inside(f[Eigen::Index(q[a])]))
            visit(p, a, q[a]);
      }
  };
  tbb::parallel_for(0, nx, [&](int i) {
    int c = 0;
    for_edges_in_slab(i, [&](std::size_t, int, std::size_t) { ++c; });
    slab_count[std::size_t(i) + 1] = c;
  });
  for (int i = 0; i < nx; ++i) slab_count[std::size_t(i) + 1] += slab_count[std::size_t(i)];
  Mesh mesh;
  mesh.vertices.resize(slab_count.back(), 3);
  const Eigen::Vector3d h = grid.spacing();
  auto position = [&](std::size_t p) {
    const int k = int(p % std::size_t(nz)), j = int((p / std::size_t(nz)) % std::size_t(ny)),
              i = int(p / (std::size_t(nz) * ny));
    return Eigen::Vector3d(grid.bounds.min + Eigen::Vector3d(i * h[0], j * h[1], k * h[2]));
  };
  tbb::parallel_for(0, nx, [&](int i) {
    int next = slab_count[std::size_t(i)];
    for_edges_in_slab(i, [&](std::size_t p, int a, std::size_t q) {
      vertex_id[3 * p + std::size_t(a)] = next;
      mesh.vertices.row(next++) =
          crossing(position(p), f[Eigen::Index(p)], position(q), f[Eigen::Index(q)]).transpose();
    });
  });

  // 2. Polygons per cube, traced around its faces; triangles collected per slab, in order.
  std::vector<detail::PolygonOutput> slab_output(static_cast<std::size_t>(std::max(nx - 1, 0)));
  tbb::parallel_for(0, nx - 1, [&](int i) {
    detail::PolygonOutput& slab = slab_output[std::size_t(i)];
    for (int j = 0; j + 1 < ny; ++j)
      for (int k = 0; k + 1 < nz; ++k) {
        double value[8];
        std::size_t corner_point[8];
        int mask = 0;
        for (int c = 0; c < 8; ++c) {
          corner_point[c] = grid.index(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1));
          value[c] = f[Eigen::Index(corner_point[c])];
          mask |= inside(value[c]) << c;
        }
        if (mask == 0 || mask == 255) continue;
        detail::cube_polygons(value, [&](const int* edges, int size) {
          int polygon[12];
          Eigen::Vector3d position[12];
          for (int q = 0; q < size; ++q) {
            polygon[q] = vertex_id[3 * corner_point[T.edge_low_corner[edges[q]]] +
                                   std::size_t(edges[q] / 4)];
            position[q] = mesh.vertices.row(polygon[q]).transpose();
          }
          detail::triangulate_polygon(polygon, edges, position, size, slab);
        });
      }
  });
  // Concatenate the slabs in order; centroid vertices (negative ids) go after the edge vertices.
  std::size_t total = 0, extra = 0;
  for (const auto& s : slab_output) total += s.triangles.size(), extra += s.centroids.size();
  const Eigen::Index edge_vertices = mesh.vertices.rows();
  mesh.vertices.conservativeResize(edge_vertices + Eigen::Index(extra), 3);
  mesh.triangles.resize(Eigen::Index(total), 3);
  Eigen::Index at = 0, next_centroid = edge_vertices;
  for (const auto& s : slab_output) {
    for (const auto& c : s.centroids) mesh.vertices.row(next_centroid++) = c.transpose();
    const Eigen::Index base = next_centroid - Eigen::Index(s.centroids.size());
    for (const auto& t : s.triangles) {
      for (int k = 0; k < 3; ++k)
        mesh.triangles(at, k) =
            t[std::size_t(k)] >= 0 ? t[std::size_t(k)] : int(base) - t[std::size_t(k)] - 1;
      ++at;
    }
  }
  return mesh;
}

}  // namespace sdfcontour
