#include "reconstruction/local/lattice_subdivision.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>

namespace sdfcontour::detail {

namespace {

constexpr std::uint64_t kInside = std::uint64_t(1) << 63;

struct KeyedPosition {
  VertexKey key;
  Eigen::Vector3d position;
  char on_feature = 0;
};

// The vertex at j / n of the way from level-0 vertex x to y, named and placed from the end with
// the smaller key.
KeyedPosition on_edge(const KeyedTriangles& in, int x, int y, int j, int n) {
  std::uint64_t kx = in.vertex_key[std::size_t(x)], ky = in.vertex_key[std::size_t(y)];
  const char fx = in.on_feature[std::size_t(x)], fy = in.on_feature[std::size_t(y)];
  if (j == 0) return {{kx, 0}, in.vertices.row(x).transpose(), fx};
  if (j == n) return {{ky, 0}, in.vertices.row(y).transpose(), fy};
  if (kx > ky) std::swap(kx, ky), std::swap(x, y), j = n - j;
  const double t = double(j) / n;
  return {{kx, (ky + 1) * 64 + std::uint64_t(j)},
          (1 - t) * in.vertices.row(x).transpose() + t * in.vertices.row(y).transpose(),
          char(fx && fy)};
}

}  // namespace

SubdividedMesh lattice_subdivision(const KeyedTriangles& in, int levels) {
  const int n = 1 << levels;
  const Eigen::Index f = in.triangles.rows();
  // Lattice point (u, v): u steps towards the triangle's 2nd vertex, v towards its 3rd.
  const int points = (n + 1) * (n + 2) / 2;
  auto slot = [n](int u, int v) { return u * (n + 1) + v; };
  std::vector<KeyedPosition> all(std::size_t(f) * std::size_t(points));
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    const int a = in.triangles(t, 0), b = in.triangles(t, 1), c = in.triangles(t, 2);
    const Eigen::Vector3d pa = in.vertices.row(a).transpose(), pb = in.vertices.row(b).transpose(),
                          pc = in.vertices.row(c).transpose();
    KeyedPosition* out = all.data() + std::size_t(t) * std::size_t(points);
    for (int u = 0, i = 0; u <= n; ++u)
      for (int v = 0; u + v <= n; ++v, ++i) {
        if (v == 0)
          out[i] = on_edge(in, a, b, u, n);
        else if (u == 0)
          out[i] = on_edge(in, a, c, v, n);
        else if (u + v == n)
          out[i] = on_edge(in, b, c, v, n);
        else
          out[i] = {{kInside | in.triangle_name[std::size_t(t)], std::uint64_t(slot(u, v))},
                    (double(n - u - v) / n) * pa + (double(u) / n) * pb + (double(v) / n) * pc};
      }
  });
  std::vector<std::pair<VertexKey, std::size_t>> order(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) order[i] = {all[i].key, i};
  tbb::parallel_sort(order.begin(), order.end());
  SubdividedMesh out;
  std::vector<int> id(all.size());
  std::vector<std::size_t> first_of;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || order[i].first != order[i - 1].first) {
      out.keys.push_back(order[i].first);
      first_of.push_back(order[i].second);
    }
    id[order[i].second] = int(out.keys.size()) - 1;
  }
  out.mesh.vertices.resize(Eigen::Index(first_of.size()), 3);
  out.on_feature.resize(first_of.size());
  for (std::size_t v = 0; v < first_of.size(); ++v) {
    out.mesh.vertices.row(Eigen::Index(v)) = all[first_of[v]].position.transpose();
    out.on_feature[v] = all[first_of[v]].on_feature;
  }
  const int children = n * n;
  out.mesh.triangles.resize(f * children, 3);
  out.parent.resize(std::size_t(f * children));
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    const int* ids = id.data() + std::size_t(t) * std::size_t(points);
    auto at = [&](int u, int v) {
      // Slots are numbered row by row (u), v within: rows shrink by one each.
      return ids[u * (n + 1) - u * (u - 1) / 2 + v];
    };
    Eigen::Index r = t * children;
    for (int u = 0; u < n; ++u)
      for (int v = 0; u + v < n; ++v) {
        out.mesh.triangles.row(r++) << at(u, v), at(u + 1, v), at(u, v + 1);
        if (u + v + 2 <= n)
          out.mesh.triangles.row(r++) << at(u + 1, v), at(u + 1, v + 1), at(u, v + 1);
      }
    for (Eigen::Index k = t * children; k < (t + 1) * children; ++k)
      out.parent[std::size_t(k)] = in.triangle_name[std::size_t(t)];
  });
  return out;
}

}  // namespace sdfcontour::detail
