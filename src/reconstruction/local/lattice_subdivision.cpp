#include "reconstruction/local/lattice_subdivision.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>

#include "pipeline/uninitialised_allocator.h"
#include "reconstruction/carving_internal.h"
#include "reconstruction/chord_offsets.h"
#include "reconstruction/mesh_geometry.h"
#include "sdfcontour/reconstruction/contact_projection.h"

namespace sdfcontour::detail {

namespace {

constexpr std::uint64_t kInside = std::uint64_t(1) << 63;

// Points are named by their place on the finest lattice (kFinestLattice segments per edge), so
// that a point keeps its name at every level: split_curved_edges' midpoints are named as one
// more uniform level would name them.
constexpr int kFinestLattice = 32;

std::uint64_t inside_slot(int u, int v, int n) {
  const int s = kFinestLattice / n;
  return std::uint64_t(u * s) * (kFinestLattice + 1) + std::uint64_t(v * s);
}

// (No default member values: a large array of them is first written by the parallel loop that
// fills it.)
struct KeyedPosition {
  VertexKey key;
  Eigen::Vector3d position;
  char on_feature;
};

}  // namespace

template <>
struct LeftUnwritten<KeyedPosition> : std::true_type {};  // (Eigen's vector writes nothing)

namespace {

// The vertex at j / n of the way from level-0 vertex x to y, named and placed from the end with
// the smaller key.
KeyedPosition on_edge(const KeyedTriangles& in, int x, int y, int j, int n) {
  std::uint64_t kx = in.vertex_key[std::size_t(x)], ky = in.vertex_key[std::size_t(y)];
  const char fx = in.on_feature[std::size_t(x)], fy = in.on_feature[std::size_t(y)];
  if (j == 0) return {{kx, 0}, in.vertices.row(x).transpose(), fx};
  if (j == n) return {{ky, 0}, in.vertices.row(y).transpose(), fy};
  if (kx > ky) std::swap(kx, ky), std::swap(x, y), j = n - j;
  const double t = double(j) / n;
  return {{kx, (ky + 1) * 64 + std::uint64_t(j * (kFinestLattice / n))},
          (1 - t) * in.vertices.row(x).transpose() + t * in.vertices.row(y).transpose(),
          char(fx && fy)};
}

// Lattice point (u, v) of level-0 triangle t cut into n (u steps towards its 2nd vertex, v
// towards its 3rd): named, placed, and on a sharp feature where its level-0 edge's ends both are.
KeyedPosition lattice_point(const KeyedTriangles& in, Eigen::Index t, int u, int v, int n) {
  const int a = in.triangles(t, 0), b = in.triangles(t, 1), c = in.triangles(t, 2);
  if (v == 0) return on_edge(in, a, b, u, n);
  if (u == 0) return on_edge(in, a, c, v, n);
  if (u + v == n) return on_edge(in, b, c, v, n);
  return {{kInside | in.triangle_name[std::size_t(t)], inside_slot(u, v, n)},
          (double(n - u - v) / n) * in.vertices.row(a).transpose() +
              (double(u) / n) * in.vertices.row(b).transpose() +
              (double(v) / n) * in.vertices.row(c).transpose(),
          char(0)};
}

// The lattice coordinates (u, v) of the corners of child k of a triangle cut into n x n, in the
// order lattice_subdivision makes them.
std::vector<std::array<std::array<int, 2>, 3>> child_corners(int n) {
  std::vector<std::array<std::array<int, 2>, 3>> out;
  for (int u = 0; u < n; ++u)
    for (int v = 0; u + v < n; ++v) {
      out.push_back({{{u, v}, {u + 1, v}, {u, v + 1}}});
      if (u + v + 2 <= n) out.push_back({{{u + 1, v}, {u + 1, v + 1}, {u, v + 1}}});
    }
  return out;
}

// Points made once per triangle that holds them, merged by name: the distinct keys ascending, per
// key its first point, and per point its vertex.
// Left unwritten when sized: the parallel loops that fill these fault their pages in (zeroed
// first, millions of entries at 256^3 were zeroed on one thread).
// (A struct, not a std::pair: a pair's constructor zeroes it.)
struct KeyedIndex {
  VertexKey key;
  std::size_t index;
  bool operator<(const KeyedIndex& o) const {
    return key < o.key || (key == o.key && index < o.index);
  }
};
using KeyedIndices = Unwritten<KeyedIndex>;

struct KeyOrder {
  std::vector<VertexKey> keys;
  Unwritten<std::size_t> first_of;
  Unwritten<int> id;
};

KeyOrder order_by_key(KeyedIndices order) {
  tbb::parallel_sort(order.begin(), order.end());
  // Each distinct key's rank, counted in blocks of the sorted list (in parallel), then the blocks'
  // counts summed in order.
  const std::size_t count = order.size(), block = 1 << 16, blocks = (count + block - 1) / block;
  auto starts_key = [&](std::size_t i) { return i == 0 || order[i].key != order[i - 1].key; };
  std::vector<std::size_t> before(blocks + 1, 0);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    for (std::size_t i = b * block; i < std::min(count, (b + 1) * block); ++i)
      before[b + 1] += starts_key(i);
  });
  for (std::size_t b = 0; b < blocks; ++b) before[b + 1] += before[b];
  KeyOrder out;
  out.id.resize(count);
  out.keys.resize(before.back());
  out.first_of.resize(before.back());
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    std::size_t rank = before[b];
    for (std::size_t i = b * block; i < std::min(count, (b + 1) * block); ++i) {
      if (starts_key(i)) {
        out.keys[rank] = order[i].key;
        out.first_of[rank++] = order[i].index;
      }
      out.id[order[i].index] = int(rank) - 1;
    }
  });
  return out;
}

// Level 0: the input's used vertices in ascending key order, as the general path would make them,
// without naming every triangle's corners (edge fans' meshes at bunny 256^3: 2.8 M corners sorted,
// 0.4 s on one thread). Nothing where two vertices share a key.
std::optional<SubdividedMesh> unsubdivided(const KeyedTriangles& in) {
  const std::size_t count = in.vertex_key.size();
  std::vector<char> is_used(count, 0);
  for (Eigen::Index t = 0; t < in.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) is_used[std::size_t(in.triangles(t, c))] = 1;
  std::vector<int> used;
  KeyedIndices order;
  for (std::size_t v = 0; v < count; ++v)
    if (is_used[v]) {
      order.push_back({{in.vertex_key[v], 0}, used.size()});
      used.push_back(int(v));
    }
  KeyOrder named = order_by_key(std::move(order));
  if (named.keys.size() != used.size()) return std::nullopt;
  SubdividedMesh out;
  out.keys = std::move(named.keys);
  out.mesh.vertices.resize(Eigen::Index(used.size()), 3);
  out.on_feature.resize(used.size());
  // (Each loop writes distinct places: in parallel, as they are millions at 512^3.)
  tbb::parallel_for(std::size_t(0), used.size(), [&](std::size_t i) {
    const int v = used[named.first_of[i]];
    out.mesh.vertices.row(Eigen::Index(i)) = in.vertices.row(v);
    out.on_feature[i] = in.on_feature[std::size_t(v)];
  });
  std::vector<int> id(count, -1);
  tbb::parallel_for(std::size_t(0), used.size(),
                    [&](std::size_t i) { id[std::size_t(used[i])] = named.id[i]; });
  out.mesh.triangles.resize(in.triangles.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), in.triangles.rows(), [&](Eigen::Index t) {
    for (int c = 0; c < 3; ++c) out.mesh.triangles(t, c) = id[std::size_t(in.triangles(t, c))];
  });
  out.parent = in.triangle_name;
  out.child.assign(in.triangle_name.size(), 0);
  return out;
}

}  // namespace

SubdividedMesh lattice_subdivision(const KeyedTriangles& in, int levels) {
  if (levels == 0)
    if (auto same = unsubdivided(in)) return std::move(*same);
  const int n = 1 << levels;
  const Eigen::Index f = in.triangles.rows();
  // Lattice point (u, v): u steps towards the triangle's 2nd vertex, v towards its 3rd.
  const int points = (n + 1) * (n + 2) / 2;
  Unwritten<KeyedPosition> all(std::size_t(f) * std::size_t(points));
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    KeyedPosition* out = all.data() + std::size_t(t) * std::size_t(points);
    for (int u = 0, i = 0; u <= n; ++u)
      for (int v = 0; u + v <= n; ++v, ++i) out[i] = lattice_point(in, t, u, v, n);
  });
  KeyedIndices order(all.size());
  tbb::parallel_for(std::size_t(0), all.size(), [&](std::size_t i) { order[i] = {all[i].key, i}; });
  KeyOrder named = order_by_key(std::move(order));
  const Unwritten<std::size_t>& first_of = named.first_of;
  const Unwritten<int>& id = named.id;
  SubdividedMesh out;
  out.keys = std::move(named.keys);
  out.mesh.vertices.resize(Eigen::Index(first_of.size()), 3);
  out.on_feature.resize(first_of.size());
  tbb::parallel_for(std::size_t(0), first_of.size(), [&](std::size_t v) {
    out.mesh.vertices.row(Eigen::Index(v)) = all[first_of[v]].position.transpose();
    out.on_feature[v] = all[first_of[v]].on_feature;
  });
  const int children = n * n;
  const auto corners = child_corners(n);
  out.mesh.triangles.resize(f * children, 3);
  out.parent.resize(std::size_t(f * children));
  out.child.resize(std::size_t(f * children));
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    const int* ids = id.data() + std::size_t(t) * std::size_t(points);
    auto at = [&](int u, int v) {
      // Slots are numbered row by row (u), v within: rows shrink by one each.
      return ids[u * (n + 1) - u * (u - 1) / 2 + v];
    };
    Eigen::Index r = t * children;
    for (const auto& [p, q, w] : corners)
      out.mesh.triangles.row(r++) << at(p[0], p[1]), at(q[0], q[1]), at(w[0], w[1]);
    for (Eigen::Index k = t * children; k < (t + 1) * children; ++k) {
      out.parent[std::size_t(k)] = in.triangle_name[std::size_t(t)];
      out.child[std::size_t(k)] = int(k - t * children);
    }
  });
  return out;
}

std::vector<char> shared_corners(const SubdividedMesh& sub) {
  std::vector<char> out(sub.on_feature.size(), 0);
  for (std::size_t v = 0; v < out.size(); ++v) out[v] = sub.on_feature[v] == 2;
  return out;
}

SplitMesh split_curved_edges(const KeyedTriangles& in, const SubdividedMesh& fine, int levels,
                             const std::function<bool(int, int)>& split) {
  const int n = 1 << levels;
  const int children = n * n;
  const Eigen::Index f = in.triangles.rows();
  const auto corners = child_corners(n);
  struct NewPoint {
    VertexKey key;
    std::array<int, 2> source;
    char on_feature;
  };
  // Which of each child's edges split (bit e: from corner e to e + 1), then per level-0
  // triangle its children's pieces (fine's vertex ids, or -1 - k for its k-th new point) and new
  // points, in flat arrays at the triangle's offsets.
  auto ids = [&](Eigen::Index t, int k, int id[3]) {
    for (int c = 0; c < 3; ++c) id[c] = fine.mesh.triangles(t * children + k, c);
  };
  Unwritten<unsigned char> masks(std::size_t(f) * std::size_t(children));
  Unwritten<std::size_t> first_new(std::size_t(f) + 1), first_piece(std::size_t(f) + 1);
  first_new[0] = first_piece[0] = 0;
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    std::size_t made = 0;
    for (int k = 0; k < children; ++k) {
      int id[3];
      ids(t, k, id);
      unsigned char mask = 0;
      // Vertex ids ascend with keys: (min, max) asks the same of both triangles on the edge.
      for (int e = 0; e < 3; ++e)
        if (split(std::min(id[e], id[(e + 1) % 3]), std::max(id[e], id[(e + 1) % 3])))
          mask |= (unsigned char)(1 << e), ++made;
      masks[std::size_t(t) * std::size_t(children) + std::size_t(k)] = mask;
    }
    first_new[std::size_t(t) + 1] = made;
    first_piece[std::size_t(t) + 1] = made + std::size_t(children);  // each split adds a piece
  });
  for (Eigen::Index t = 0; t < f; ++t) {
    first_new[std::size_t(t) + 1] += first_new[std::size_t(t)];
    first_piece[std::size_t(t) + 1] += first_piece[std::size_t(t)];
  }
  Unwritten<NewPoint> points(first_new.back());
  Unwritten<std::array<int, 3>> pieces(first_piece.back());
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    NewPoint* made = points.data() + first_new[std::size_t(t)];
    std::array<int, 3>* out = pieces.data() + first_piece[std::size_t(t)];
    int count = 0;
    for (int k = 0; k < children; ++k) {
      int id[3], mid[3];
      ids(t, k, id);
      const unsigned char mask = masks[std::size_t(t) * std::size_t(children) + std::size_t(k)];
      int splits = 0;
      for (int e = 0; e < 3; ++e) {
        const int x = id[e], y = id[(e + 1) % 3];
        mid[e] = 0;
        if (!(mask & (1 << e))) continue;
        const auto& cx = corners[std::size_t(k)][std::size_t(e)];
        const auto& cy = corners[std::size_t(k)][std::size_t((e + 1) % 3)];
        const KeyedPosition p = lattice_point(in, t, cx[0] + cy[0], cx[1] + cy[1], 2 * n);
        made[count++] = {p.key, {std::min(x, y), std::max(x, y)}, p.on_feature};
        mid[e] = -count;
        ++splits;
      }
      const int a = id[0], b = id[1], c = id[2], ab = mid[0], bc = mid[1], ca = mid[2];
      if (splits == 0) {
        *out++ = {a, b, c};
      } else if (splits == 3) {
        *out++ = {a, ab, ca};
        *out++ = {ab, b, bc};
        *out++ = {ca, bc, c};
        *out++ = {ab, bc, ca};
      } else if (splits == 1) {
        if (ab) *out++ = {a, ab, c}, *out++ = {ab, b, c};
        if (bc) *out++ = {a, b, bc}, *out++ = {a, bc, c};
        if (ca) *out++ = {a, b, ca}, *out++ = {ca, b, c};
      } else {
        // Two split edges: the corner between them is cut off, the rest is cut at its shorter
        // diagonal's fixed choice (from the unsplit edge's first end).
        if (!ca) *out++ = {ab, b, bc}, *out++ = {a, ab, bc}, *out++ = {a, bc, c};
        if (!ab) *out++ = {bc, c, ca}, *out++ = {b, bc, ca}, *out++ = {b, ca, a};
        if (!bc) *out++ = {ca, a, ab}, *out++ = {c, ca, ab}, *out++ = {c, ab, b};
      }
    }
  });
  // Every vertex, old and new, named; new points shared by two triangles are made twice alike.
  const std::size_t old = std::size_t(fine.mesh.vertices.rows());
  KeyedIndices order(old + points.size());
  tbb::parallel_for(std::size_t(0), old, [&](std::size_t v) { order[v] = {fine.keys[v], v}; });
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t q) {
    order[old + q] = {points[q].key, old + q};
  });
  KeyOrder named = order_by_key(std::move(order));
  const Unwritten<std::size_t>& first_of = named.first_of;
  const Unwritten<int>& id = named.id;
  SplitMesh out;
  out.sub.keys = std::move(named.keys);
  const std::size_t count = first_of.size();
  out.source.resize(count);
  out.sub.on_feature.resize(count);
  out.sub.mesh.vertices.resize(Eigen::Index(count), 3);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t v) {
    const std::size_t s = first_of[v];
    if (s < old) {
      out.source[v] = {int(s), int(s)};
      out.sub.on_feature[v] = fine.on_feature[s];
    } else {
      const NewPoint& p = points[s - old];
      out.source[v] = p.source;
      out.sub.on_feature[v] = p.on_feature;
    }
    const auto [x, y] = out.source[v];
    out.sub.mesh.vertices.row(Eigen::Index(v)) =
        0.5 * (fine.mesh.vertices.row(x) + fine.mesh.vertices.row(y));
  });
  const Eigen::Index total = Eigen::Index(pieces.size());
  out.sub.mesh.triangles.resize(total, 3);
  out.sub.parent.resize(std::size_t(total));
  out.sub.child.resize(std::size_t(total));
  tbb::parallel_for(Eigen::Index(0), f, [&](Eigen::Index t) {
    const std::size_t new_at = old + first_new[std::size_t(t)];
    for (std::size_t r = first_piece[std::size_t(t)]; r < first_piece[std::size_t(t) + 1]; ++r) {
      for (int c = 0; c < 3; ++c) {
        const int v = pieces[r][std::size_t(c)];
        out.sub.mesh.triangles(Eigen::Index(r), c) =
            v >= 0 ? id[std::size_t(v)] : id[new_at + std::size_t(-v - 1)];
      }
      out.sub.parent[r] = in.triangle_name[std::size_t(t)];
      out.sub.child[r] = int(r - first_piece[std::size_t(t)]);
    }
  });
  return out;
}

// Normals that turn by more than 30 degrees along an edge (the benchmark's sharp edges' dihedral
// angle) cross a crease.
const double kCreaseTurnCosine = std::cos(30.0 * M_PI / 180.0);

bool chord_sags(const SubdividedMesh& sub, const PointMatrix& normals, int x, int y, double limit) {
  // Not along a sharp edge (straight), nor across a crease (its normals turn by more than
  // kCreaseTurn; the fit is least sure next to it): only where the surface curves.
  if (sub.on_feature[std::size_t(x)] && sub.on_feature[std::size_t(y)]) return false;
  const double c = std::clamp(normals.row(x).dot(normals.row(y)), -1.0, 1.0);
  if (c < kCreaseTurnCosine) return false;
  const double length = (sub.mesh.vertices.row(x) - sub.mesh.vertices.row(y)).norm();
  // The turn t lies between its chord 2 sin(t/2) and 1.05 times it below the crease's 30
  // degrees: the arc cosine only where those bounds disagree (most edges sag far less).
  const double chord = std::sqrt(2 * (1 - c));
  if (length * chord * 1.05 / 8 <= limit) return false;
  return length * std::acos(c) / 8 > limit;
}

// (lattice_subdivision.h) An edge whose ends' normals turn by t radians over its length L sags by
// about L t / 8.
namespace {

// The chord offsets of the vertices kept from before a split (`kept`, in the new numbering)
// set again for their triangles in `mesh` (in spacings of `spacing`): the first projection made
// them for the triangles before the split, whose sag is up to four times their new ones' (the
// exact torus at 64^3 lay 6.8e-4 h outside on average without the carving). All offsets are
// made from the positions before any moves, so the result is the same in any order.
void offset_again(const std::vector<char>& kept, double spacing, Mesh& mesh, ChordOffsets& chords) {
  std::vector<char> skip(kept.size());
  for (std::size_t v = 0; v < kept.size(); ++v) skip[v] = !kept[v] || chords.offset[v] == 0;
  const VertexTriangles around(mesh, &skip);
  std::vector<double> next(kept.size(), 0.0);
  const EdgeMoments edges(mesh, around, spacing);
  tbb::parallel_for(std::size_t(0), kept.size(), [&](std::size_t v) {
    const Eigen::Index at = Eigen::Index(v);
    if (skip[v] || edges.triangles(at) == 0) return;
    next[v] = chord_offset(chords.form[v], edges.sum(at), edges.triangles(at));
  });
  for (std::size_t v = 0; v < kept.size(); ++v) {
    if (skip[v] || next[v] == chords.offset[v]) continue;
    mesh.vertices.row(Eigen::Index(v)) +=
        ((next[v] - chords.offset[v]) * spacing) * chords.normal[v].transpose();
    chords.offset[v] = next[v];
  }
}

}  // namespace

void split_sagging_edges(const KeyedTriangles& near, int levels, double limit,
                         const ContactProjector& projector, const LocalBrickOptions& options,
                         const VertexTriangles& around, SubdividedMesh& sub,
                         PointMatrix& reconstructed, std::vector<char>& corners,
                         ChordOffsets* chords) {
  const PointMatrix normals = vertex_normals(sub.mesh, around);
  auto split = [&](int x, int y) { return chord_sags(sub, normals, x, y, limit); };
  SplitMesh split_mesh = split_curved_edges(near, sub, levels, split);
  PointMatrix start(split_mesh.sub.mesh.vertices.rows(), 3);
  std::vector<char> stay(split_mesh.source.size(), 0);
  tbb::parallel_for(std::size_t(0), stay.size(), [&](std::size_t v) {
    const auto [x, y] = split_mesh.source[v];
    start.row(Eigen::Index(v)) = 0.5 * (reconstructed.row(x) + reconstructed.row(y));
    stay[v] = x == y || (options.keep_features && split_mesh.sub.on_feature[v]);
  });
  sub = std::move(split_mesh.sub);
  reconstructed = std::move(start);
  corners = shared_corners(sub);
  std::vector<char> kept;
  if (chords && chords->size() > 0) {
    ChordOffsets before = std::move(*chords);
    chords->resize(stay.size());
    kept.assign(stay.size(), 0);
    for (std::size_t v = 0; v < stay.size(); ++v) {
      const auto [x, y] = split_mesh.source[v];
      if (x != y || std::size_t(x) >= before.size()) continue;
      kept[v] = 1;
      chords->offset[v] = before.offset[std::size_t(x)];
      chords->normal[v] = before.normal[std::size_t(x)];
      chords->form[v] = before.form[std::size_t(x)];
    }
  }
  projector.project(sub.mesh, &stay, chords);
  if (!kept.empty()) offset_again(kept, projector.spacing(), sub.mesh, *chords);
}

}  // namespace sdfcontour::detail
