#include "reconstruction/poisson/sign_constraints.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <queue>

#include "reconstruction/poisson/bspline.h"

namespace sdfcontour::poisson {

namespace {

// Where a unit-cube point takes chi from (Indicator::locate), with the cell's corner nodes.
struct Location : Indicator::Location {
  std::array<int, 8> nodes{};
};

// The located samples by cube of side `reach`: the samples within reach of one.
class SampleBuckets {
 public:
  SampleBuckets(const std::vector<Eigen::Vector3d>& unit, const std::vector<Location>& where,
                double reach)
      : unit_(unit), reach_(reach * (1 + 1e-6)) {  // slack for the bump's rounding
    for (std::size_t s = 0; s < unit.size(); ++s)
      if (where[s].depth >= 0) sorted_.push_back({key(bucket(unit[s])), int(s)});
    std::sort(sorted_.begin(), sorted_.end());
  }
  /// Calls f(q) for every located sample q within reach of sample s (s included).
  template <class F>
  void near(int s, F&& f) const {
    const auto b = bucket(unit_[std::size_t(s)]);
    for (long i = b[0] - 1; i <= b[0] + 1; ++i)
      for (long j = b[1] - 1; j <= b[1] + 1; ++j)
        for (long k = b[2] - 1; k <= b[2] + 1; ++k) {
          if (i < 0 || j < 0 || k < 0) continue;
          const Key at = key({i, j, k});
          for (auto it =
                   std::lower_bound(sorted_.begin(), sorted_.end(), std::pair<Key, int>{at, -1});
               it != sorted_.end() && it->first == at; ++it)
            if ((unit_[std::size_t(it->second)] - unit_[std::size_t(s)]).norm() <= reach_)
              f(it->second);
        }
  }

 private:
  std::array<long, 3> bucket(const Eigen::Vector3d& u) const {
    return {long(u[0] / reach_), long(u[1] / reach_), long(u[2] / reach_)};
  }
  static Key key(const std::array<long, 3>& b) { return pack(b[0], b[1], b[2]); }
  const std::vector<Eigen::Vector3d>& unit_;
  double reach_;
  std::vector<std::pair<Key, int>> sorted_;
};

}  // namespace

SignCorrection enforce_signs(Indicator& chi, double iso, const SignedSamples& sides,
                             const UnitPoints& frame, const SignConstraintOptions& options) {
  SignCorrection result;
  const Octree& tree = chi.tree();
  const Eigen::Index m = sides.points.rows();
  std::vector<Location> where(static_cast<std::size_t>(m));
  std::vector<Eigen::Vector3d> unit(static_cast<std::size_t>(m));
  tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index s) {
    unit[std::size_t(s)] = frame.to_unit(sides.points.row(s).transpose());
    const Eigen::Vector3d& u = unit[std::size_t(s)];
    if (!(u.array() >= 0).all() || !(u.array() < 1).all()) return;
    Location& at = where[std::size_t(s)];
    static_cast<Indicator::Location&>(at) = chi.locate(u);
    if (at.depth >= 0) at.nodes = tree.level(at.depth).corner_nodes(at.cell);
  });
  const double radius_unit = options.radius / frame.size;
  // Adds gap * k(|node - p|) / sum_c w_c k_c to the nodes within the radius, k(d) = (1 -
  // d^2/r^2)^2: chi(p) moves by exactly gap, its surroundings smoothly less.
  auto bump = [&](const OctreeLevel& L, std::vector<double>& x, const Eigen::Vector3d& p,
                  const Location& at, const std::array<double, 8>& w, double gap) {
    const double r = radius_unit * double(L.res);  // in cells of L
    auto kernel = [&](long i, long j, long k) {
      const double d2 =
          (Eigen::Vector3d(double(i), double(j), double(k)) - p * double(L.res)).squaredNorm() /
          (r * r);
      return d2 < 1 ? (1 - d2) * (1 - d2) : 0.0;
    };
    double at_p = 0;
    for (int c = 0; c < 8; ++c)
      at_p += w[std::size_t(c)] *
              kernel(at.cell[0] + (c & 1), at.cell[1] + (c >> 1 & 1), at.cell[2] + (c >> 2 & 1));
    if (!(at_p > 0)) return;
    const double scale = gap / at_p;
    const long reach = long(std::ceil(r));
    // A line of nodes (fixed i, j) at a time: one search for its first node in reach.
    for (long i = std::max(at.cell[0] - reach, 0L); i <= at.cell[0] + 1 + reach; ++i)
      for (long j = std::max(at.cell[1] - reach, 0L); j <= at.cell[1] + 1 + reach; ++j) {
        const auto line = L.node_lines.line(i, j);
        const Key first = pack(i, j, std::max(at.cell[2] - reach, 0L)),
                  last = pack(i, j, at.cell[2] + 1 + reach);
        for (auto it =
                 std::lower_bound(L.nodes.begin() + line[0], L.nodes.begin() + line[1], first);
             it != L.nodes.begin() + line[1] && *it <= last; ++it) {
          const double kv = kernel(i, j, long(*it & kKeyMask));
          if (kv == 0) continue;
          const int node = int(it - L.nodes.begin());
          x[std::size_t(node)] += scale * kv;
        }
      }
  };
  // Each margin is measured once, on the solved chi: measured on the corrected chi it would
  // chase its own corrections.
  std::vector<double> margin(static_cast<std::size_t>(m), -1.0);
  // Whether sample s is off its side; with `fix`, chi moves (a bump, or its cell's corners) so
  // that it is not.
  auto visit = [&](Eigen::Index s, bool fix) {
    const Location& at = where[std::size_t(s)];
    const double value = sides.values[s];
    if (at.depth < 0 || value == 0 || !std::isfinite(value)) return false;
    const OctreeLevel& L = tree.level(at.depth);
    std::vector<double>& x = chi.values(at.depth);
    const Eigen::Vector3d& p = unit[std::size_t(s)];
    const auto w = corner_weights(p, at.cell, L.res);
    Eigen::Vector3d t;
    for (int a = 0; a < 3; ++a) t[a] = p[a] * double(L.res) - double(at.cell[std::size_t(a)]);
    // chi and its gradient in the cell (trilinear).
    double v = 0;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int c = 0; c < 8; ++c) {
      const double xc = x[std::size_t(at.nodes[std::size_t(c)])];
      v += w[std::size_t(c)] * xc;
      for (int a = 0; a < 3; ++a) {
        double d = (c >> a & 1) ? 1.0 : -1.0;
        for (int b = 0; b < 3; ++b)
          if (b != a) d *= (c >> b & 1) ? t[b] : 1.0 - t[b];
        g[a] += d * xc * double(L.res);
      }
    }
    double& ms = margin[std::size_t(s)];
    if (ms < 0) ms = options.margin * std::abs(value) / frame.size * g.norm();
    // Inside: chi >= iso + margin; outside: chi <= iso - margin.
    const double slack = (1 - options.trigger) * ms;  // of the margin, tolerated
    const double gap = (value < 0 ? iso + ms : iso - ms) - v;
    if (value < 0 ? gap <= slack : gap >= -slack) return false;
    if (fix) {
      if (radius_unit <= 0) {
        double sum_w2 = 0;
        for (const double wc : w) sum_w2 += wc * wc;
        for (int c = 0; c < 8; ++c)
          x[std::size_t(at.nodes[std::size_t(c)])] += gap * w[std::size_t(c)] / sum_w2;
      } else {
        bump(L, x, p, at, w, gap);
      }
    }
    return true;
  };
  // A correction at sample s moves nodes within the bump's radius of it (radius 0: its cell's
  // corners), so it can change the verdict only of samples within that plus a cell diagonal.
  double diagonal = 0;
  for (const Location& at : where)
    if (at.depth >= 0) diagonal = std::max(diagonal, std::sqrt(3.0) * tree.level(at.depth).h);
  const SampleBuckets buckets(unit, where, (radius_unit > 0 ? radius_unit : diagonal) + diagonal);
  // Which samples are violated, in parallel (chi is only read; each sample writes only its own
  // margin and flag).
  std::vector<char> violated(static_cast<std::size_t>(m), 0);
  auto recount = [&](const std::vector<int>& samples) {
    tbb::parallel_for(std::size_t(0), samples.size(), [&](std::size_t q) {
      violated[std::size_t(samples[q])] = visit(samples[q], false);
    });
    return std::count(violated.begin(), violated.end(), 1);
  };
  std::vector<int> all(static_cast<std::size_t>(m));
  for (std::size_t q = 0; q < all.size(); ++q) all[q] = int(q);
  result.violations = result.violations_left = recount(all);
  // A sweep corrects, in sample order, each sample violated when its turn comes. Only samples
  // violated before the sweep or near one corrected earlier in it can be: a queue in sample
  // order holds just those (the same corrections as visiting every sample).
  std::vector<char> queued(static_cast<std::size_t>(m), 0);
  while (result.violations_left > 0 && result.sweeps < options.max_sweeps) {
    std::priority_queue<int, std::vector<int>, std::greater<int>> queue;
    for (Eigen::Index s = 0; s < m; ++s)
      if (violated[std::size_t(s)]) queue.push(int(s)), queued[std::size_t(s)] = 1;
    std::vector<int> touched;  // samples whose verdict a correction may have changed
    while (!queue.empty()) {
      const int s = queue.top();
      queue.pop();
      queued[std::size_t(s)] = 0;
      if (!visit(s, true)) continue;
      buckets.near(s, [&](int q) {
        touched.push_back(q);
        if (q > s && !queued[std::size_t(q)]) queue.push(q), queued[std::size_t(q)] = 1;
      });
    }
    ++result.sweeps;
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    result.violations_left = recount(touched);
  }
  return result;
}

}  // namespace sdfcontour::poisson
