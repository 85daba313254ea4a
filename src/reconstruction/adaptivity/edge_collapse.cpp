// Greedy quadric edge collapse on flat arrays: a heap of edges by cost, each vertex's triangles
// in a list. CGAL's Surface_mesh_simplification did the same with a half-edge mesh and its
// policies at about 23 us a merge (bunny 256^3, TOL 0.02); the merges were 80% of adaptivity.
#include "reconstruction/adaptivity/edge_collapse.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <queue>
#include <tuple>
#include <unordered_set>
#include <utility>

#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour::detail {

namespace {

using Triangle = std::array<int, 3>;

// An edge's entry in the heap: valid while both ends keep the versions they had when pushed.
struct Entry {
  double cost, length;
  int a, b;  // a < b
  unsigned version_a, version_b;
  // The heap's top is the cheapest (costs under 1e-12 count as 0: a flat region's merges are
  // equal), then the shortest, then by the edge's ends: the same order every run.
  bool operator<(const Entry& o) const {
    return std::tie(cost, length, a, b) > std::tie(o.cost, o.length, o.a, o.b);
  }
};

// A triangle's corners and their vertices.
struct Corners {
  std::array<Eigen::Vector3d, 3> at;
  std::array<int, 3> ids;
  Eigen::Vector3d normal() const { return (at[1] - at[0]).cross(at[2] - at[0]); }
  Eigen::AlignedBox3d box() const {
    Eigen::AlignedBox3d b(at[0]);
    b.extend(at[1]), b.extend(at[2]);
    return b;
  }
};

// A triangle's plane for orientation tests in floating point: the sign of d's side where
// rounding cannot change it, else 0.
struct SurePlane {
  Eigen::Vector3d a, normal;
  double scale;  // |b - a|^2 |c - a|^2: the determinant's rounding grows with it
  explicit SurePlane(const Corners& t)
      : a(t.at[0]),
        normal((t.at[1] - t.at[0]).cross(t.at[2] - t.at[0])),
        scale((t.at[1] - t.at[0]).squaredNorm() * (t.at[2] - t.at[0]).squaredNorm()) {}
  int side(const Eigen::Vector3d& d) const {
    const Eigen::Vector3d w = d - a;
    const double det = normal.dot(w);
    if (det * det <= 1e-24 * scale * w.squaredNorm()) return 0;
    return det > 0 ? 1 : -1;
  }
};

// True where floating point alone shows that two triangles meet at most in what they share (the
// exact test is left for the rest): sharing an edge, they are not coplanar; sharing a corner,
// the edge of one opposite it lies on one side of the other's plane; sharing nothing, one lies
// on one side of the other's plane.
bool clearly_apart(const Corners& s, const Corners& t) {
  int shared = 0, si = 0, ti = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (s.ids[std::size_t(i)] == t.ids[std::size_t(j)]) ++shared, si = i, ti = j;
  if (shared == 3) return false;
  const SurePlane ps(s);
  if (shared == 2) {
    for (std::size_t j = 0; j < 3; ++j)
      if (t.ids[j] != s.ids[0] && t.ids[j] != s.ids[1] && t.ids[j] != s.ids[2])
        return ps.side(t.at[j]) != 0;
  }
  // The corners of y other than `skip` (-1: all) on one side of x's plane.
  auto one_side = [](const SurePlane& x, const Corners& y, int skip) {
    int first = 0;
    for (int k = 0; k < 3; ++k) {
      if (k == skip) continue;
      const int p = x.side(y.at[std::size_t(k)]);
      if (p == 0 || (first != 0 && p != first)) return false;
      first = p;
    }
    return true;
  };
  const int skip_t = shared == 1 ? ti : -1, skip_s = shared == 1 ? si : -1;
  return one_side(ps, t, skip_t) || one_side(SurePlane(t), s, skip_s);
}

class Collapser {
 public:
  Collapser(const Mesh& mesh, std::vector<MergeQuadric>& quadrics, const std::vector<char>& frozen,
            const CollapseLimits& limits)
      : quadrics_(quadrics),
        frozen_(frozen),
        limits_(limits),
        min_cosine_(std::cos(limits.max_normal_turn * std::acos(-1.0) / 180)) {
    const std::size_t n = std::size_t(mesh.vertices.rows());
    points_.resize(n);
    for (std::size_t v = 0; v < n; ++v) points_[v] = mesh.vertices.row(Eigen::Index(v)).transpose();
    triangles_.resize(std::size_t(mesh.triangles.rows()));
    std::vector<int> count(n + 1, 0);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.triangles(Eigen::Index(t), k);
        if (v < 0 || std::size_t(v) >= n)
          throw Error("adaptivity: a triangle's vertex is out of range");
        triangles_[t][std::size_t(k)] = v;
        ++count[std::size_t(v)];
      }
    star_.resize(n);
    for (std::size_t v = 0; v < n; ++v) star_[v].reserve(std::size_t(count[v]));
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (int v : triangles_[t]) star_[std::size_t(v)].push_back(int(t));
    alive_.assign(triangles_.size(), 1);
    seen_.assign(triangles_.size(), 0);
    removed_.assign(n, 0);
    version_.assign(n, 0);
    blocked_.resize(n);
  }

  long run() {
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int a = triangles_[t][std::size_t(k)], b = triangles_[t][std::size_t(k + 1) % 3];
        if (a < b)
          push(a, b);  // each edge once (a closed star holds it both ways)
        else if (!has_edge_from(b, a, int(t)))
          push(b, a);  // a border edge: only this way
      }
    long merges = 0;
    while (!heap_.empty()) {
      const Entry e = heap_.top();
      heap_.pop();
      if (removed_[std::size_t(e.a)] || removed_[std::size_t(e.b)] ||
          version_[std::size_t(e.a)] != e.version_a || version_[std::size_t(e.b)] != e.version_b)
        continue;
      const std::optional<Eigen::Vector3d> x = placement(e.a, e.b);
      // A refused edge comes back when a merge next to either end pushes it anew.
      if (!x || !collapsible(e.a, e.b, *x)) {
        refused_.insert(key(e.a, e.b));
        blocked_[std::size_t(e.a)].push_back(e.b), blocked_[std::size_t(e.b)].push_back(e.a);
        continue;
      }
      collapse(e.a, e.b, *x);
      ++merges;
    }
    return merges;
  }

  Mesh result(std::vector<int>& source) const {
    std::vector<int> row(points_.size(), -1);
    source.clear();
    for (std::size_t v = 0; v < points_.size(); ++v)
      if (!removed_[v]) row[v] = int(source.size()), source.push_back(int(v));
    Mesh out;
    out.vertices.resize(Eigen::Index(source.size()), 3);
    for (std::size_t r = 0; r < source.size(); ++r)
      out.vertices.row(Eigen::Index(r)) = points_[std::size_t(source[r])].transpose();
    const long kept = std::count(alive_.begin(), alive_.end(), char(1));
    out.triangles.resize(Eigen::Index(kept), 3);
    Eigen::Index r = 0;
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      if (!alive_[t]) continue;
      for (int k = 0; k < 3; ++k)
        out.triangles(r, k) = row[std::size_t(triangles_[t][std::size_t(k)])];
      ++r;
    }
    return out;
  }

 private:
  // True if triangle `other` (not `t`) of a's star holds the edge b -> a.
  bool has_edge_from(int b, int a, int t) const {
    for (int s : star_[std::size_t(a)]) {
      if (s == t) continue;
      const Triangle& T = triangles_[std::size_t(s)];
      for (int k = 0; k < 3; ++k)
        if (T[std::size_t(k)] == b && T[std::size_t(k + 1) % 3] == a) return true;
    }
    return false;
  }

  MergeQuadric merged(int a, int b) const {
    return quadrics_[std::size_t(a)] + quadrics_[std::size_t(b)];
  }

  // Where the merged vertex goes: a corner keeps its place; two corners stay two; a minimiser
  // far from the edge extrapolates (nearly parallel planes) and merges nothing.
  std::optional<Eigen::Vector3d> placement(int a, int b) const {
    if (frozen_[std::size_t(a)] || frozen_[std::size_t(b)]) return std::nullopt;
    const bool pinned_a = quadrics_[std::size_t(a)].pinned,
               pinned_b = quadrics_[std::size_t(b)].pinned;
    if (pinned_a && pinned_b) return std::nullopt;
    if (pinned_a) return points_[std::size_t(a)];
    if (pinned_b) return points_[std::size_t(b)];
    const Eigen::Vector3d mid = (points_[std::size_t(a)] + points_[std::size_t(b)]) / 2;
    const Eigen::Vector3d x = merged(a, b).minimiser(mid);
    if (!x.allFinite() || (x - mid).norm() > 2 * limits_.spacing) return std::nullopt;
    return x;
  }

  void push(int a, int b) {
    const std::optional<Eigen::Vector3d> x = placement(a, b);
    if (!x) return;
    const double h2 = limits_.spacing * limits_.spacing;
    const double cost = merged(a, b).at(*x) / h2;
    // An edge over the bound never merges: only a merge next to it changes its cost.
    if (cost > limits_.tolerance * limits_.tolerance) return;
    const double rounded = cost < 1e-12 ? 0.0 : cost;
    heap_.push({rounded, (points_[std::size_t(a)] - points_[std::size_t(b)]).squaredNorm(), a, b,
                version_[std::size_t(a)], version_[std::size_t(b)]});
  }

  // The other vertices of v's star, sorted, each once.
  std::vector<int> neighbours(int v) const {
    std::vector<int> out;
    for (int t : star_[std::size_t(v)])
      for (int u : triangles_[std::size_t(t)])
        if (u != v) out.push_back(u);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // The link condition (the ends share exactly the two vertices opposite their edge), no triangle
  // of the star flipped or turned past the bound, and no crossing next to it.
  bool collapsible(int a, int b, const Eigen::Vector3d& x) const {
    std::vector<int> opposite;
    for (int t : star_[std::size_t(a)]) {
      const Triangle& T = triangles_[std::size_t(t)];
      if (T[0] != b && T[1] != b && T[2] != b) continue;
      for (int u : T)
        if (u != a && u != b) opposite.push_back(u);
    }
    if (opposite.size() != 2 || opposite[0] == opposite[1]) return false;
    const std::vector<int> na = neighbours(a), nb = neighbours(b);
    std::vector<int> common;
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
    if (common.size() != 2) return false;
    std::vector<Corners> star;  // the merged vertex's triangles, as they would be
    for (int v : {a, b})
      for (int t : star_[std::size_t(v)]) {
        const Triangle& T = triangles_[std::size_t(t)];
        const bool has_a = T[0] == a || T[1] == a || T[2] == a;
        const bool has_b = T[0] == b || T[1] == b || T[2] == b;
        if (has_a && has_b) continue;  // vanishes
        Corners after;
        std::array<Eigen::Vector3d, 3> p;
        for (std::size_t k = 0; k < 3; ++k) {
          p[k] = points_[std::size_t(T[k])];
          const bool merging = T[k] == a || T[k] == b;
          after.at[k] = merging ? x : p[k];
          after.ids[k] = merging ? a : T[k];
        }
        const Eigen::Vector3d before = (p[1] - p[0]).cross(p[2] - p[0]);
        const Eigen::Vector3d now = after.normal();
        const double norms = before.norm() * now.norm();
        if (!(norms > 0) || before.dot(now) < min_cosine_ * norms) return false;
        star.push_back(after);
      }
    return !crosses_nearby(a, b, star, na, nb);
  }

  // Whether a triangle of the merged vertex's `star` would cross another of it, or one of the
  // triangles around it (those of its link's vertices): the folds that the normal bound lets
  // through where neighbouring triangles already turn sharply (bunny 64^3, TOL 0.005: six
  // crossing pairs, each within 0.2 h, which a second round of merges had to freeze).
  bool crosses_nearby(int a, int b, const std::vector<Corners>& star, const std::vector<int>& na,
                      const std::vector<int>& nb) const {
    // Each triangle once: the star's marked first, so that only the others join the ring.
    if (++ring_id_ == 0) std::fill(seen_.begin(), seen_.end(), 0u), ring_id_ = 1;
    for (int v : {a, b})
      for (int t : star_[std::size_t(v)]) seen_[std::size_t(t)] = ring_id_;
    std::vector<int>& ring = ring_;
    ring.clear();
    for (const std::vector<int>* link : {&na, &nb})
      for (int u : *link)
        if (u != a && u != b)
          for (int t : star_[std::size_t(u)])
            if (seen_[std::size_t(t)] != ring_id_)
              seen_[std::size_t(t)] = ring_id_, ring.push_back(t);
    auto cross = [](const Corners& s, const Corners& t) {
      return !clearly_apart(s, t) && !collinear_corners(s.at) && !collinear_corners(t.at) &&
             triangles_cross(s.at, s.ids, t.at, t.ids);
    };
    std::vector<Corners> around(ring.size());
    std::vector<Eigen::AlignedBox3d> boxes(ring.size());
    for (std::size_t r = 0; r < ring.size(); ++r) {
      for (std::size_t k = 0; k < 3; ++k) {
        around[r].ids[k] = triangles_[std::size_t(ring[r])][k];
        around[r].at[k] = points_[std::size_t(around[r].ids[k])];
      }
      boxes[r] = around[r].box();
    }
    for (std::size_t i = 0; i < star.size(); ++i) {
      for (std::size_t j = i + 1; j < star.size(); ++j)
        if (cross(star[i], star[j])) return true;
      const Eigen::AlignedBox3d box = star[i].box();
      for (std::size_t r = 0; r < ring.size(); ++r)
        if (box.intersects(boxes[r]) && cross(star[i], around[r])) return true;
    }
    return false;
  }

  // b merges into a (the lower index stays): the edge's two triangles vanish, b's others take a.
  void collapse(int a, int b, const Eigen::Vector3d& x) {
    std::vector<int>& sa = star_[std::size_t(a)];
    sa.erase(std::remove_if(sa.begin(), sa.end(),
                            [&](int t) {
                              const Triangle& T = triangles_[std::size_t(t)];
                              return T[0] == b || T[1] == b || T[2] == b;
                            }),
             sa.end());
    for (int t : star_[std::size_t(b)]) {
      Triangle& T = triangles_[std::size_t(t)];
      if (T[0] == a || T[1] == a || T[2] == a) {
        alive_[std::size_t(t)] = 0;
        for (int u : T)
          if (u != a && u != b) {
            auto& su = star_[std::size_t(u)];
            su.erase(std::find(su.begin(), su.end(), t));
          }
        continue;
      }
      for (int& u : T)
        if (u == b) u = a;
      sa.push_back(t);
    }
    star_[std::size_t(b)].clear();
    removed_[std::size_t(b)] = 1;
    quadrics_[std::size_t(a)] = merged(a, b);
    points_[std::size_t(a)] = x;
    ++version_[std::size_t(a)];
    // a's edges cost anew (their entries from before are stale); the refused edges next to the
    // merge may pass now.
    const std::vector<int> around = neighbours(a);
    for (int u : around) {
      refused_.erase(key(std::min(a, u), std::max(a, u)));
      push(std::min(a, u), std::max(a, u));
    }
    for (int v : around) {
      std::vector<int> ends;
      ends.swap(blocked_[std::size_t(v)]);
      for (int u : ends)
        if (!removed_[std::size_t(u)] && refused_.erase(key(std::min(u, v), std::max(u, v))))
          push(std::min(u, v), std::max(u, v));
    }
    blocked_[std::size_t(a)].clear(), blocked_[std::size_t(b)].clear();
  }

  long long key(int a, int b) const { return (long long)a * (long long)points_.size() + b; }

  std::vector<MergeQuadric>& quadrics_;
  const std::vector<char>& frozen_;
  const CollapseLimits& limits_;
  const double min_cosine_;  // of the largest turn a triangle of a merge's star may take
  std::vector<Eigen::Vector3d> points_;
  std::vector<Triangle> triangles_;
  std::vector<std::vector<int>> star_;  // each vertex's triangles
  std::vector<char> alive_, removed_;
  std::vector<unsigned> version_;
  std::priority_queue<Entry> heap_;
  mutable std::vector<unsigned> seen_;  // per triangle: the last crossing test that read it
  mutable unsigned ring_id_ = 0;
  mutable std::vector<int> ring_;
  std::unordered_set<long long> refused_;  // edges refused since their ends last changed
  std::vector<std::vector<int>> blocked_;  // per vertex: the other ends of its refused edges
};

}  // namespace

Mesh collapse_edges(const Mesh& mesh, std::vector<MergeQuadric>& quadrics,
                    const std::vector<char>& frozen, const CollapseLimits& limits,
                    std::vector<int>& source, long& merges) {
  Collapser c(mesh, quadrics, frozen, limits);
  merges += c.run();
  return c.result(source);
}

}  // namespace sdfcontour::detail
