#include "reconstruction/adaptivity/brick_merging.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <tuple>
#include <utility>

namespace sdfcontour::detail {

namespace {

using BrickKey = std::int64_t;

// The brick of each vertex, its lattice coordinates packed in 21 bits each.
std::vector<BrickKey> brick_of_vertices(const PointMatrix& V, const Eigen::Vector3d& origin,
                                        double side, double shift) {
  std::vector<BrickKey> key(std::size_t(V.rows()));
  constexpr double kLast = double((1 << 21) - 1);
  tbb::parallel_for(Eigen::Index(0), V.rows(), [&](Eigen::Index v) {
    BrickKey k = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor((V(v, a) - origin[a]) / side + shift);
      k = (k << 21) | BrickKey(std::clamp(c, 0.0, kLast));
    }
    key[std::size_t(v)] = k;
  });
  return key;
}

// What one brick changed: its merged vertices' new places and quadrics, the vertices it merged
// away, and the triangles that replace its movable vertices' stars (global indices).
struct BrickChanges {
  std::vector<int> moved;
  std::vector<Eigen::Vector3d> places;
  std::vector<MergeQuadric> quadrics;
  std::vector<int> removed;
  std::vector<std::array<int, 3>> triangles;
  long merges = 0;
};

// Tiny union-find over corner nodes.
int root(std::vector<int>& parent, int i) {
  while (parent[std::size_t(i)] != i)
    i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
  return i;
}

// The piece of brick `key` (triangles `tris`, ascending), merged. The brick's own vertices keep
// one local vertex each; any other vertex gets one per fan of the piece's triangles around it,
// so that the piece is 2-manifold with borders (those vertices lie two rings from any movable
// one: no link condition reads them).
BrickChanges merge_brick(const MergeState& state, const std::vector<BrickKey>& owner,
                         const std::vector<char>& movable, const std::vector<char>& near,
                         BrickKey key, const std::vector<int>& tris, const CollapseLimits& limits) {
  const auto& T = state.mesh.triangles;
  auto inner = [&](int v) { return near[std::size_t(v)] && owner[std::size_t(v)] == key; };
  std::vector<int> global;  // local vertex -> global vertex
  for (int t : tris)
    for (int k = 0; k < 3; ++k)
      if (inner(T(t, k))) global.push_back(T(t, k));
  std::sort(global.begin(), global.end());
  global.erase(std::unique(global.begin(), global.end()), global.end());
  const int inner_count = int(global.size());
  auto inner_local = [&](int v) {
    return int(std::lower_bound(global.begin(), global.begin() + inner_count, v) - global.begin());
  };

  // Other vertices: one node per (vertex, triangle) corner, joined across shared edges.
  std::vector<std::pair<int, int>> corners;      // (vertex, local triangle)
  std::vector<std::tuple<int, int, int>> edges;  // (vertex, other end, local triangle)
  for (int i = 0; i < int(tris.size()); ++i)
    for (int k = 0; k < 3; ++k) {
      const int b = T(tris[std::size_t(i)], k);
      if (inner(b)) continue;
      corners.emplace_back(b, i);
      edges.emplace_back(b, T(tris[std::size_t(i)], (k + 1) % 3), i);
      edges.emplace_back(b, T(tris[std::size_t(i)], (k + 2) % 3), i);
    }
  std::sort(corners.begin(), corners.end());
  std::sort(edges.begin(), edges.end());
  auto node = [&](int b, int i) {
    return int(std::lower_bound(corners.begin(), corners.end(), std::make_pair(b, i)) -
               corners.begin());
  };
  std::vector<int> parent(corners.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t e = 1; e < edges.size(); ++e) {
    const auto& [b0, x0, i0] = edges[e - 1];
    const auto& [b1, x1, i1] = edges[e];
    if (b0 == b1 && x0 == x1)
      parent[std::size_t(root(parent, node(b0, i0)))] = root(parent, node(b1, i1));
  }
  std::vector<int> copy(corners.size(), -1);  // root node -> local vertex
  for (std::size_t c = 0; c < corners.size(); ++c) {
    const int r = root(parent, int(c));
    if (copy[std::size_t(r)] < 0) {
      copy[std::size_t(r)] = int(global.size());
      global.push_back(corners[c].first);
    }
  }

  Mesh piece;
  piece.vertices.resize(Eigen::Index(global.size()), 3);
  std::vector<MergeQuadric> quadrics(global.size());
  std::vector<char> frozen(global.size(), 1);
  for (std::size_t l = 0; l < global.size(); ++l) {
    piece.vertices.row(Eigen::Index(l)) = state.mesh.vertices.row(global[l]);
    if (int(l) < inner_count) {
      quadrics[l] = state.quadrics[std::size_t(global[l])];
      frozen[l] = !movable[std::size_t(global[l])];
    }
  }
  piece.triangles.resize(Eigen::Index(tris.size()), 3);
  for (int i = 0; i < int(tris.size()); ++i)
    for (int k = 0; k < 3; ++k) {
      const int b = T(tris[std::size_t(i)], k);
      piece.triangles(i, k) =
          inner(b) ? inner_local(b) : copy[std::size_t(root(parent, node(b, i)))];
    }

  BrickChanges changes;
  std::vector<int> source;
  const Mesh merged = collapse_edges(piece, quadrics, frozen, limits, source, changes.merges);
  std::vector<int> row_of(global.size(), -1);  // local vertex -> its row in `merged`
  for (std::size_t r = 0; r < source.size(); ++r) row_of[std::size_t(source[r])] = int(r);
  for (int l = 0; l < inner_count; ++l) {
    const int g = global[std::size_t(l)];
    if (!movable[std::size_t(g)]) continue;
    if (row_of[std::size_t(l)] < 0) {
      changes.removed.push_back(g);
    } else {
      changes.moved.push_back(g);
      changes.places.push_back(merged.vertices.row(row_of[std::size_t(l)]).transpose());
      changes.quadrics.push_back(quadrics[std::size_t(l)]);
    }
  }
  for (Eigen::Index t = 0; t < merged.triangles.rows(); ++t) {
    std::array<int, 3> tri;
    bool changed = false;
    for (int k = 0; k < 3; ++k) {
      const int l = source[std::size_t(merged.triangles(t, k))];
      tri[std::size_t(k)] = global[std::size_t(l)];
      changed |= l < inner_count && movable[std::size_t(global[std::size_t(l)])];
    }
    if (changed) changes.triangles.push_back(tri);
  }
  return changes;
}

}  // namespace

long merge_in_bricks(MergeState& state, const Eigen::Vector3d& origin, double brick_side,
                     double shift, const CollapseLimits& limits) {
  const auto& V = state.mesh.vertices;
  const auto& T = state.mesh.triangles;
  const std::vector<BrickKey> owner = brick_of_vertices(V, origin, brick_side, shift);
  // Movable: not frozen, every neighbour in the same brick. Near: movable or next to one.
  std::vector<char> seam(std::size_t(V.rows()), 0), movable(seam.size()), near(seam.size(), 0);
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const BrickKey a = owner[std::size_t(T(t, 0))];
    if (owner[std::size_t(T(t, 1))] != a || owner[std::size_t(T(t, 2))] != a)
      for (int k = 0; k < 3; ++k) seam[std::size_t(T(t, k))] = 1;
  }
  for (std::size_t v = 0; v < seam.size(); ++v) movable[v] = !seam[v] && !state.frozen[v];
  std::vector<char> star(std::size_t(T.rows()), 0);  // a triangle a merge may change
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    if (movable[std::size_t(T(t, 0))] || movable[std::size_t(T(t, 1))] ||
        movable[std::size_t(T(t, 2))]) {
      star[std::size_t(t)] = 1;
      for (int k = 0; k < 3; ++k) near[std::size_t(T(t, k))] = 1;
    }
  // Each brick's piece: the triangles around its near vertices.
  std::vector<std::pair<BrickKey, int>> entries;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = T(t, k);
      if (!near[std::size_t(v)]) continue;
      bool first = true;  // each brick once per triangle
      for (int j = 0; j < k; ++j)
        first &=
            !(near[std::size_t(T(t, j))] && owner[std::size_t(T(t, j))] == owner[std::size_t(v)]);
      if (first) entries.emplace_back(owner[std::size_t(v)], int(t));
    }
  tbb::parallel_sort(entries.begin(), entries.end());
  std::vector<std::pair<BrickKey, std::vector<int>>> bricks;
  for (const auto& [key, t] : entries) {
    if (bricks.empty() || bricks.back().first != key) bricks.push_back({key, {}});
    bricks.back().second.push_back(t);
  }
  std::vector<BrickChanges> changes(bricks.size());
  tbb::parallel_for(std::size_t(0), bricks.size(), [&](std::size_t b) {
    changes[b] =
        merge_brick(state, owner, movable, near, bricks[b].first, bricks[b].second, limits);
  });

  // Joined in brick order: the unchanged triangles as they were, then each brick's.
  MergeState out;
  std::vector<char> removed(seam.size(), 0);
  Eigen::MatrixX3d places = V;
  long merges = 0;
  for (const BrickChanges& c : changes) {
    merges += c.merges;
    for (int g : c.removed) removed[std::size_t(g)] = 1;
    for (std::size_t i = 0; i < c.moved.size(); ++i) {
      places.row(c.moved[i]) = c.places[i].transpose();
      state.quadrics[std::size_t(c.moved[i])] = c.quadrics[i];
    }
  }
  std::vector<int> index(seam.size(), -1);
  for (std::size_t v = 0; v < seam.size(); ++v)
    if (!removed[v]) {
      index[v] = int(out.source.size());
      out.source.push_back(state.source[v]);
      out.frozen.push_back(state.frozen[v]);
      out.quadrics.push_back(state.quadrics[v]);
    }
  out.mesh.vertices.resize(Eigen::Index(out.source.size()), 3);
  for (std::size_t v = 0; v < seam.size(); ++v)
    if (index[v] >= 0) out.mesh.vertices.row(index[v]) = places.row(Eigen::Index(v));
  std::vector<std::array<int, 3>> triangles;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    if (!star[std::size_t(t)]) triangles.push_back({T(t, 0), T(t, 1), T(t, 2)});
  for (const BrickChanges& c : changes)
    triangles.insert(triangles.end(), c.triangles.begin(), c.triangles.end());
  out.mesh.triangles.resize(Eigen::Index(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      out.mesh.triangles(Eigen::Index(t), k) = index[std::size_t(triangles[t][std::size_t(k)])];
  state = std::move(out);
  return merges;
}

}  // namespace sdfcontour::detail
