#include "sign_constraints.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "bspline.h"

namespace sdfcontour::poisson {

namespace {

// Where a unit-cube point takes chi from (Indicator::locate), with the cell's corner nodes.
struct Location : Indicator::Location {
  std::array<int, 8> nodes{};
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
  // Per depth, the nodes a correction moved during the current sweep.
  std::vector<std::vector<char>> moved(tree.levels.size());
  std::vector<std::pair<int, int>> moved_list;
  auto mark_moved = [&](int depth, int node) {
    auto& flags = moved[std::size_t(depth)];
    if (flags.empty()) flags.assign(tree.level(depth).nodes.size(), 0);
    if (!flags[std::size_t(node)])
      flags[std::size_t(node)] = 1, moved_list.push_back({depth, node});
  };
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
          x[std::size_t(node)] += scale * kv, mark_moved(L.depth, node);
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
    const double gap = (value < 0 ? iso + ms : iso - ms) - v;
    if (value < 0 ? gap <= 0 : gap >= 0) return false;
    if (fix) {
      if (radius_unit <= 0) {
        double sum_w2 = 0;
        for (const double wc : w) sum_w2 += wc * wc;
        for (int c = 0; c < 8; ++c) {
          x[std::size_t(at.nodes[std::size_t(c)])] += gap * w[std::size_t(c)] / sum_w2;
          mark_moved(at.depth, at.nodes[std::size_t(c)]);
        }
      } else {
        bump(L, x, p, at, w, gap);
      }
    }
    return true;
  };
  // Whether any corner of sample s's cell was moved during the current sweep. A sample none of
  // whose corners moved is exactly as violated (or not) as before.
  auto corners_moved = [&](Eigen::Index s) {
    const Location& at = where[std::size_t(s)];
    if (at.depth < 0) return false;
    const auto& flags = moved[std::size_t(at.depth)];
    if (flags.empty()) return false;
    for (int c = 0; c < 8; ++c)
      if (flags[std::size_t(at.nodes[std::size_t(c)])]) return true;
    return false;
  };
  // Which samples are violated, in parallel (chi is only read; each sample writes only its own
  // margin and flag); with `all` unset, only those whose corners moved are looked at again.
  std::vector<char> violated(static_cast<std::size_t>(m), 0);
  auto count = [&](bool all) {
    tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index s) {
      if (all || corners_moved(s)) violated[std::size_t(s)] = visit(s, false);
    });
    return std::count(violated.begin(), violated.end(), 1);
  };
  // A sweep visits the samples in order and corrects each that is violated when its turn comes
  // (a sample not violated before the sweep and with no corner moved since is skipped: visiting
  // it would find it satisfied).
  auto sweep = [&]() {
    for (Eigen::Index s = 0; s < m; ++s)
      if (violated[std::size_t(s)] || corners_moved(s)) visit(s, true);
  };
  result.violations = result.violations_left = count(true);
  while (result.violations_left > 0 && result.sweeps < options.max_sweeps) {
    sweep();
    ++result.sweeps;
    result.violations_left = count(false);
    for (const auto& [depth, node] : moved_list) moved[std::size_t(depth)][std::size_t(node)] = 0;
    moved_list.clear();
  }
  return result;
}

}  // namespace sdfcontour::poisson
