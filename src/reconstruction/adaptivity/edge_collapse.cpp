// Greedy quadric edge collapse on flat arrays: a heap of edges by cost, each vertex's triangles
// in a list. CGAL's Surface_mesh_simplification did the same with a half-edge mesh and its
// policies at about 23 us a merge (bunny 256^3, TOL 0.02); the merges were 80% of adaptivity.
#include "reconstruction/adaptivity/edge_collapse.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <queue>
#include <tuple>
#include <unordered_set>
#include <utility>

namespace sdfcontour::detail {

namespace {

using Triangle = std::array<int, 3>;

// An edge's entry in the heap: valid while both ends keep the versions they had when pushed.
struct Entry {
  double cost, length;
  int a, b;  // a < b
  unsigned version_a, version_b;
  // The heap's top is the cheapest, ties broken by the edge's ends: the same order every run.
  bool operator<(const Entry& o) const {
    return std::tie(cost, length, a, b) > std::tie(o.cost, o.length, o.a, o.b);
  }
};

class Collapser {
 public:
  Collapser(const Mesh& mesh, std::vector<MergeQuadric>& quadrics, const std::vector<char>& frozen,
            const CollapseLimits& limits)
      : quadrics_(quadrics), frozen_(frozen), limits_(limits) {
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

  // The link condition (the ends share exactly the two vertices opposite their edge, each of which
  // keeps at least three neighbours), and no triangle of the star flipped or turned past the bound.
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
    // The merged vertex keeps at least three neighbours.
    if (common.size() != 2) return false;
    const double min_cosine = std::cos(limits_.max_normal_turn * std::acos(-1.0) / 180);
    for (int v : {a, b})
      for (int t : star_[std::size_t(v)]) {
        const Triangle& T = triangles_[std::size_t(t)];
        const bool has_a = T[0] == a || T[1] == a || T[2] == a;
        const bool has_b = T[0] == b || T[1] == b || T[2] == b;
        if ((has_a && has_b) || (v == b && has_a)) continue;  // vanishes
        std::array<Eigen::Vector3d, 3> p, q;
        for (std::size_t k = 0; k < 3; ++k) {
          p[k] = points_[std::size_t(T[k])];
          q[k] = T[k] == a || T[k] == b ? x : p[k];
        }
        const Eigen::Vector3d before = (p[1] - p[0]).cross(p[2] - p[0]);
        const Eigen::Vector3d after = (q[1] - q[0]).cross(q[2] - q[0]);
        const double norms = before.norm() * after.norm();
        if (!(norms > 0) || before.dot(after) < min_cosine * norms) return false;
      }
    return true;
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
  std::vector<Eigen::Vector3d> points_;
  std::vector<Triangle> triangles_;
  std::vector<std::vector<int>> star_;  // each vertex's triangles
  std::vector<char> alive_, removed_;
  std::vector<unsigned> version_;
  std::priority_queue<Entry> heap_;
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
