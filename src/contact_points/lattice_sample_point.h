// Internal: one band sample's contact point from the grid's lattice (lattice_contact_points.h):
// its gradient, the candidate, the empty-sphere filter and the rescues.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "contact_points/convex_cell.h"
#include "contact_points/lattice_gradient.h"
#include "contact_points/lattice_spheres.h"
#include "contact_points/orthocentre.h"
#include "sdfcontour/contact_points/contact_points.h"

namespace sdfcontour::detail::lattice_points {

// A sample whose neighbours miss its gradient's prediction by more than the options'
// max_slope_miss but by no more than this still slides onto its sphere out of the others' (after
// the power vertex): at the inner end of a slot thinner than a spacing (penguin 128^3) those are
// the only points. Farther misses lie across creases and medial axes, where the slide ends off the
// surface (with any miss: the cube at 64^3 0.6 h off, armadillo 128^3 1.4x MC's L-infinity).
constexpr double kSlideSlopeMiss = 0.55;

// Gradients shorter than this have no usable direction.
constexpr double kTinyGradient = 1e-300;

// A power vertex is looked for within this many spacings (in each direction) of where the
// gradient puts the point (the triangulation's are the orthocentres of the sample's own
// tetrahedra). Armadillo 32^3: 0.25 keeps 13,211 points at a median distance of 0.0004 h (the
// triangulation 13,726 at 0.0014 h) in 0.51 s, 1 keeps 16,044 at 0.0001 h in 1.13 s (the
// triangulation 0.32 s, the lattice without power vertices 6,426 at 0.0044 h).
constexpr double kPowerBox = 0.25;

// The samples whose points lie in one box of this many spacings a side read the spheres gathered
// for it.
constexpr double kListBox = 3.0;

// How far beyond a sphere the first rescues read: the slide's first round (half a spacing) and
// kPowerBox's box.
inline double near_start_reach(const Eigen::Vector3d& h) {
  return std::max(h.minCoeff() / 2, std::sqrt(3.0) * kPowerBox * h.maxCoeff());
}

enum class Outcome : char { Skipped, ZeroGradient, Discarded, Kept, Rescued };

// One sample's point: its gradient from the lattice, the candidate, the filter and the rescues.
class SamplePoint {
 public:
  SamplePoint(const Lattice& lattice, const ContactPointOptions& options, long s)
      : l_(lattice), o_(options), s_(s), p_(lattice.point(s)), v_(lattice.value(s)) {}

  // First the gradient and where it puts the point (start()); false if it has none.
  bool prepare() {
    gather_neighbours();
    if (!gradient(g_)) return false;
    start_ = p_ - v_ * g_.normalized();
    return true;
  }

  // The same with the gradient that an earlier prepare() found (gradient()).
  void prepare(const Eigen::Vector3d& found) {
    gather_neighbours();
    g_ = found;
    start_ = p_ - v_ * g_.normalized();
  }
  const Eigen::Vector3d& gradient() const { return g_; }

  // Then, reading `list` for the points in its box, the slope test, the candidate, then the
  // rescues (within the options' rescue_reach): a slide, and a vertex of the sample's power cell
  // on its sphere (the triangulation's rescue). A sample across a crease has the latter, then the
  // slide only if it misses the slope by no more than kSlideSlopeMiss. (A near miss's rescue stays
  // off: on the lattice it kept points 0.016 h off a box's medial planes where the filter alone
  // keeps none.)
  Outcome solve(const detail::SphereList* list) {
    list_ = list;
    const bool rescue =
        !(o_.rescue_reach > 0) || std::abs(v_) <= o_.rescue_reach * l_.spacing().maxCoeff();
    if (o_.max_slope_miss > 0 && misses_linear_prediction(g_, o_.max_slope_miss)) {
      if (!rescue) return Outcome::Discarded;
      if (power_vertex()) return Outcome::Rescued;
      const bool slight = !misses_linear_prediction(g_, kSlideSlopeMiss);
      return slight && v_ != 0 && slide(start_) ? Outcome::Rescued : Outcome::Discarded;
    }
    if (candidate(g_)) return Outcome::Kept;
    if (rescue && v_ != 0 && (slide(start_) || power_vertex())) return Outcome::Rescued;
    return Outcome::Discarded;
  }

  const Eigen::Vector3d& start() const { return start_; }
  long sample() const { return s_; }

  Eigen::Vector3d point, normal;

 private:
  // Lattice::any_sphere_near and any_sphere_holding, from the gathered list where it covers c.
  template <class F>
  bool any_sphere_near(const Eigen::Vector3d& c, double extra, F&& f) const {
    if (list_ && list_->covers(c, extra))
      return list_->any_sphere_near(c, extra, s_, std::forward<F>(f));
    return l_.any_sphere_near(c, extra, s_, std::forward<F>(f));
  }
  template <class F>
  bool any_sphere_holding(const Eigen::Vector3d& c, F&& f) const {
    return any_sphere_near(c, 0.0, std::forward<F>(f));
  }

  // The band samples around this one, read column by column once: its 3x3x3 block, and two
  // steps along each axis.
  void gather_neighbours() {
    const std::array<int, 3>& at = at_ = l_.index(s_);
    long centre[5];
    l_.along(at[0], at[1], at[2] - 2, at[2] + 2, centre);
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj) {
        long* column = &block_[std::size_t((di + 1) * 9 + (dj + 1) * 3)];
        if (di == 0 && dj == 0)
          std::copy(centre + 1, centre + 4, column);
        else
          l_.along(at[0] + di, at[1] + dj, at[2] - 1, at[2] + 1, column);
      }
    l_.along(at[0] - 2, at[1], at[2], at[2], &two_steps_[0][0]);
    l_.along(at[0] + 2, at[1], at[2], at[2], &two_steps_[0][1]);
    l_.along(at[0], at[1] - 2, at[2], at[2], &two_steps_[1][0]);
    l_.along(at[0], at[1] + 2, at[2], at[2], &two_steps_[1][1]);
    two_steps_[2][0] = centre[0];
    two_steps_[2][1] = centre[4];
  }

  // The band sample at offset (di, dj, dk), each in -1..1, or -1.
  long neighbour(int di, int dj, int dk) const {
    return block_[std::size_t((di + 1) * 9 + (dj + 1) * 3 + dk + 1)];
  }

  // The value of the band sample `offset` (-2..2) steps along `axis`, if there is one.
  bool value_at(int axis, int offset, double& out) const {
    if (offset == 0) {
      out = v_;
      return true;
    }
    long t;
    if (offset == 2 || offset == -2) {
      t = two_steps_[std::size_t(axis)][offset > 0];
    } else {
      std::array<int, 3> d{0, 0, 0};
      d[std::size_t(axis)] = offset;
      t = neighbour(d[0], d[1], d[2]);
    }
    if (t < 0) return false;
    out = l_.value(t);
    return true;
  }

  // Per axis, axis_slope()'s rules (lattice_gradient.h).
  bool gradient(Eigen::Vector3d& g) const {
    for (int a = 0; a < 3; ++a) {
      AxisStencil stencil;
      for (int k = -2; k <= 2; ++k)
        stencil.has[std::size_t(k + 2)] = value_at(a, k, stencil.v[std::size_t(k + 2)]);
      auto far = [&](int offset, double& out) {
        std::array<int, 3> at = at_;
        at[std::size_t(a)] += offset;
        long t;
        l_.along(at[0], at[1], at[2], at[2], &t);
        if (t < 0) return false;
        out = l_.value(t);
        return true;
      };
      if (!axis_slope(stencil, l_.spacing()[a], far, g[a], o_.exact_wedge_slopes)) return false;
    }
    return g.norm() > kTinyGradient && g.allFinite();
  }

  bool misses_linear_prediction(const Eigen::Vector3d& g, double slope) const {
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj)
        for (int dk = -1; dk <= 1; ++dk) {
          if (di == 0 && dj == 0 && dk == 0) continue;
          const long t = neighbour(di, dj, dk);
          if (t < 0) continue;
          const Eigen::Vector3d d = l_.point(t) - p_;
          if (std::abs(l_.value(t) - v_ - g.dot(d)) > slope * d.norm()) return true;
        }
    return false;
  }

  bool held(const Eigen::Vector3d& c) const {
    const double tau = o_.tie_tolerance;
    return any_sphere_holding(c, [&](long t, double d2) {
      const double radius =
          std::abs(l_.value(t)) - (tau > 0 ? tau * (l_.point(t) - p_).norm() : 0.0);
      return radius > 0 && d2 < radius * radius;
    });
  }

  void set(const Eigen::Vector3d& c, const Eigen::Vector3d& n) {
    point = c;
    normal = n;
  }

  bool candidate(const Eigen::Vector3d& g) {
    const Eigen::Vector3d unit = g / g.norm();
    const Eigen::Vector3d c = p_ - v_ * unit;
    if (!c.allFinite() || held(c)) return false;
    set(c, unit);
    return true;
  }

  // Pushed out of the spheres that hold it (each by its depth) and back onto the own sphere.
  bool slide(const Eigen::Vector3d& start) {
    if (!(o_.sphere_slide_rounds > 0)) return false;
    const double radius = std::abs(v_);
    // The rounds read the spheres that come within `reach` of where the list was gathered, which
    // hold every point within `reach` of there; farther, the list is gathered again.
    struct Sphere {
      Eigen::Vector3d centre;
      double radius;
    };
    thread_local std::vector<Sphere> near;
    const double reach = l_.spacing().minCoeff() / 2;
    // The first list is the one gathered at `start` (farther: the same holding spheres, in the
    // same order).
    Eigen::Vector3d gathered = start;
    near.clear();
    for (const auto& [t, d2] : near_start()) near.push_back({l_.point(t), std::abs(l_.value(t))});
    Eigen::Vector3d c = start;
    for (int round = 0; round < o_.sphere_slide_rounds; ++round) {
      if (!((c - gathered).norm() <= reach)) {
        near.clear();
        gathered = c;
        l_.any_sphere_near(c, reach, s_, [&](long t, double) {
          near.push_back({l_.point(t), std::abs(l_.value(t))});
          return false;
        });
      }
      Eigen::Vector3d push = Eigen::Vector3d::Zero();
      for (const Sphere& q : near) {
        const Eigen::Vector3d away = c - q.centre;
        // (The square root only where the sphere may hold c: most do not.)
        const double d2 = away.squaredNorm();
        if (!(d2 < q.radius * q.radius * (1 + 1e-12))) continue;
        const double d = std::sqrt(d2);
        if (d < q.radius && d > 0) push += (q.radius - d) * away / d;
      }
      if (push.squaredNorm() == 0) break;
      c = p_ + radius * (c + push - p_).normalized();
      if (!c.allFinite()) return false;
    }
    // (Farther than the radius, the gradient said little about where the point lies.)
    if ((c - start).norm() > radius) return false;
    // A point where the spheres (nearly) meet, as the triangulation's power vertex: its power to
    // each holding sphere, about 2 |value| times its depth, within the tolerance of value^2;
    // without a tolerance, the strict test with its tie tolerance. Over every sphere.
    const double tol = o_.power_vertex_tolerance / 2;
    if (tol > 0) {
      const bool deep = any_sphere_holding(c, [&](long t, double d2) {
        return std::abs(l_.value(t)) - std::sqrt(d2) > tol * radius;
      });
      if (deep) return false;
    } else if (held(c)) {
      return false;
    }
    set(c, (p_ - c) / v_);
    return true;
  }

  // The band samples (and their squared distances) whose spheres come within reach of `start_`
  // (half a spacing for the slide's first round, kPowerBox's box for the power vertex), in the
  // lattice's order: gathered once for both.
  const std::vector<std::pair<long, double>>& near_start() {
    thread_local std::vector<std::pair<long, double>> near;
    if (!gathered_) {
      near.clear();
      const double reach = near_start_reach(l_.spacing());
      any_sphere_near(start_, reach, [&](long t, double d2) {
        near.emplace_back(t, d2);
        return false;
      });
      gathered_ = true;
    }
    return near;
  }

  // A vertex of the sample's power cell, among the spheres that reach kPowerBox's box around
  // `start_`, that lies on its sphere (power within power_vertex_tolerance value^2) where it meets
  // three spheres of its side, as the triangulation's power vertices; kept where no sphere holds
  // it deeper than the tolerance allows.
  bool power_vertex() {
    const double tolerance = o_.power_vertex_tolerance;
    if (!(tolerance > 0) || v_ == 0 || !start_.allFinite()) return false;
    find_power_vertex();
    if (!(power_miss_ <= tolerance * v_ * v_)) return false;
    const double r = std::abs(v_);
    const bool deep = any_sphere_holding(power_at_, [&](long t, double d2) {
      return std::abs(l_.value(t)) - std::sqrt(d2) > tolerance / 2 * r;
    });
    if (deep) return false;
    set(power_at_, (p_ - power_at_) / v_);
    return true;
  }

  // The power vertex nearest the sphere within the tolerance (power_miss_ stays infinite if none).
  void find_power_vertex() {
    const Eigen::Vector3d& start = start_;
    const double tolerance = o_.power_vertex_tolerance;
    const double r = std::abs(v_), h = l_.spacing().maxCoeff();
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(kPowerBox * h);
    // Relative to the sample: the cell's planes are |x|^2 - v^2 <= |x - a|^2 - w for a = q - p.
    thread_local detail::ConvexCell cell;
    cell.reset((start - p_ - half).cwiseMax(Eigen::Vector3d::Constant(-2 * r)),
               (start - p_ + half).cwiseMin(Eigen::Vector3d::Constant(2 * r)));
    // Only the shell where the power to the own sphere is within the tolerance matters: within
    // the box, between the planes normal to start - p that bound it (planes -7 and -8).
    const Eigen::Vector3d axis = (start - p_) / r;
    const double outer = r * (1 + tolerance), inner = r * (1 - tolerance),
                 across2 = 3 * kPowerBox * kPowerBox * h * h;
    cell.clip(axis, outer, -7, 1e-12 * h);
    cell.clip(-axis, -std::sqrt(std::max(0.0, inner * inner - across2)), -8, 1e-12 * h);
    // Every sphere that reaches the box, gathered once: those that hold `start` cut first (they
    // cut most), then the rest mostly miss the box of what is left. The lattice's order within
    // each (the same in any brick); a plane's id is its sphere's place in `spheres`.
    thread_local std::vector<long> spheres, farther;
    spheres.clear();
    farther.clear();
    for (const auto& [t, d2] : near_start()) {
      const double radius = std::abs(l_.value(t));
      if (l_.value(t) * v_ > 0) (d2 < radius * radius ? spheres : farther).push_back(t);
    }
    spheres.insert(spheres.end(), farther.begin(), farther.end());
    for (std::size_t k = 0; k < spheres.size() && !cell.empty(); ++k) {
      const Eigen::Vector3d a = l_.point(spheres[k]) - p_;
      const double w = l_.value(spheres[k]) * l_.value(spheres[k]), length = a.norm();
      if (!(length > 0)) continue;
      cell.clip(a / length, (a.squaredNorm() - w + v_ * v_) / (2 * length), int(k), 1e-12 * h);
    }
    // The cell's vertex nearest the sphere (ties by position), its orthocentre computed once.
    const detail::ConvexCell::Vertex* nearest = nullptr;
    double best = INFINITY;
    for (const detail::ConvexCell::Vertex& x : cell.vertices()) {
      if (x.planes[0] < 0) continue;  // on the box or the shell's planes
      const double miss = std::abs(x.point.squaredNorm() - v_ * v_);
      if (miss < best || (miss == best && std::lexicographical_compare(
                                              x.point.data(), x.point.data() + 3,
                                              nearest->point.data(), nearest->point.data() + 3))) {
        best = miss;
        nearest = &x;
      }
    }
    if (!nearest) return;
    std::array<std::pair<Eigen::Vector3d, double>, 4> four;
    four[0] = {p_, v_};
    for (int k = 0; k < 3; ++k) {
      const long t = spheres[std::size_t(nearest->planes[std::size_t(k)])];
      four[std::size_t(k) + 1] = {l_.point(t), l_.value(t)};
    }
    Eigen::Vector3d centre;
    double power;
    if (!detail::orthocentre(four, centre, power) || !centre.allFinite()) return;
    const double miss = std::abs((centre - p_).squaredNorm() - v_ * v_);
    if (miss <= tolerance * v_ * v_) {
      power_miss_ = miss;
      power_at_ = centre;
    }
  }

  const Lattice& l_;
  const ContactPointOptions& o_;
  std::array<int, 3> at_;                         // the sample's place (gather_neighbours())
  std::array<long, 27> block_;                    // gather_neighbours()
  std::array<std::array<long, 2>, 3> two_steps_;  // per axis: the samples 2 steps before, after
  long s_;
  Eigen::Vector3d p_;
  double v_;
  Eigen::Vector3d g_;      // the gradient
  Eigen::Vector3d start_;  // where the gradient puts the point
  const detail::SphereList* list_ = nullptr;
  bool gathered_ = false;  // near_start()
  double power_miss_ = INFINITY;
  Eigen::Vector3d power_at_;
};

}  // namespace sdfcontour::detail::lattice_points
