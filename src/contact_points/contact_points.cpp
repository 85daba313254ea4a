#include "sdfcontour/contact_points/contact_points.h"

#include <tbb/parallel_for.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

#include "contact_points/orthocentre.h"
#include "sdfcontour/contact_points/gradients.h"

namespace sdfcontour {

namespace {

Eigen::Vector3d row(const PointMatrix& m, Eigen::Index i) {
  return m.row(i).transpose();
}

// Gradients shorter than this have no usable direction.
constexpr double kTinyGradient = 1e-300;

enum class Outcome : char { Skipped, Hidden, ZeroGradient, Discarded, Kept, Rescued };

}  // namespace

Eigen::VectorXd contact_depths(const ContactPoints& cp, const Eigen::VectorXd& values) {
  Eigen::VectorXd depths(cp.size());
  for (int q = 0; q < cp.size(); ++q) depths[q] = std::abs(values[cp.samples[std::size_t(q)]]);
  return depths;
}

bool inside_neighbour_sphere(const PointMatrix& points, const Eigen::VectorXd& values,
                             const Triangulation& tri, int i, const Eigen::Vector3d& c,
                             double tau) {
  const Eigen::Vector3d p = row(points, i);
  for (const int j : tri.neighbours(i)) {
    const Eigen::Vector3d q = row(points, j);
    const double radius = std::abs(values[j]) - (tau > 0 ? tau * (q - p).norm() : 0.0);
    if (radius > 0 && (c - q).squaredNorm() < radius * radius) return true;
  }
  return false;
}

namespace {

// Four spheres whose power at their orthocentre is within this fraction of value^2 of zero meet
// exactly, up to the rounding of float32 values (a relative 6e-8 in each distance).
constexpr double kExactMeeting = 1e-6;

// How deep the deepest of sample i's triangulation neighbours' spheres holds c (0 if none).
double neighbour_sphere_depth(const PointMatrix& points, const Eigen::VectorXd& values,
                              const Triangulation& tri, int i, const Eigen::Vector3d& c) {
  double depth = 0;
  for (const int j : tri.neighbours(i))
    depth = std::max(depth, std::abs(values[j]) - (c - row(points, j)).norm());
  return depth;
}

// Whether a triangulation neighbour of sample i misses the linear prediction from gradient g by
// more than `slope` times its distance.
bool misses_linear_prediction(const PointMatrix& points, const Eigen::VectorXd& values,
                              const Triangulation& tri, int i, const Eigen::Vector3d& g,
                              double slope) {
  const Eigen::Vector3d p = row(points, i);
  for (const int j : tri.neighbours(i)) {
    const Eigen::Vector3d d = row(points, j) - p;
    if (std::abs(values[j] - values[i] - g.dot(d)) > slope * d.norm()) return true;
  }
  return false;
}

// Point c of sample i's sphere pushed out of the neighbours' spheres it lies in (each by its
// depth) and back onto the sphere, for up to `rounds` rounds.
Eigen::Vector3d slide_out_of_spheres(const PointMatrix& points, const Eigen::VectorXd& values,
                                     const Triangulation& tri, int i, Eigen::Vector3d c,
                                     int rounds) {
  const Eigen::Vector3d p = row(points, i);
  const double radius = std::abs(values[i]);
  for (int round = 0; round < rounds; ++round) {
    Eigen::Vector3d push = Eigen::Vector3d::Zero();
    for (const int j : tri.neighbours(i)) {
      const Eigen::Vector3d away = c - row(points, j);
      const double depth = std::abs(values[j]) - away.norm();
      if (depth > 0 && away.norm() > 0) push += depth * away.normalized();
    }
    if (push.squaredNorm() == 0) break;
    c = p + radius * (c + push - p).normalized();
  }
  return c;
}

// The orthocentre of tetrahedron t (the point of equal power to its four weighted samples) and
// that power.
std::pair<Eigen::Vector3d, double> orthocentre(const PointMatrix& points,
                                               const Eigen::VectorXd& values, const TetMatrix& tets,
                                               int t) {
  std::array<std::pair<Eigen::Vector3d, double>, 4> four;
  for (int k = 0; k < 4; ++k) four[std::size_t(k)] = {row(points, tets(t, k)), values[tets(t, k)]};
  std::pair<Eigen::Vector3d, double> out;
  // (Whether the tet is flat is not asked: the caller judges the centre by its power.)
  detail::orthocentre(four, out.first, out.second);
  return out;
}

// The vertex of sample i's power cell on its sphere: the orthocentre of an incident tet of
// samples on its side with power within tolerance * value_i^2 of zero (the nearest to zero; ties
// by position), where four spheres meet.
bool power_vertex_point(const PointMatrix& points, const Eigen::VectorXd& values,
                        const Triangulation& tri, int i, double tolerance, Eigen::Vector3d& out) {
  const double limit = tolerance * values[i] * values[i];
  double best = INFINITY;
  for (const int t : tri.incident(i)) {
    bool same_side = true;
    for (int k = 0; k < 4; ++k) same_side &= values[tri.tets(t, k)] * values[i] > 0;
    if (!same_side) continue;
    const auto [centre, power] = orthocentre(points, values, tri.tets, t);
    const double miss = std::abs(power);
    if (!(miss <= limit) || !centre.allFinite()) continue;
    if (miss < best ||
        (miss == best && std::lexicographical_compare(centre.data(), centre.data() + 3, out.data(),
                                                      out.data() + 3))) {
      best = miss;
      out = centre;
    }
  }
  return best < INFINITY;
}

}  // namespace

ContactPoints gradient_contact_points(const PointMatrix& points, const Eigen::VectorXd& values,
                                      const PointMatrix& gradients, const Triangulation& tri,
                                      const ContactPointOptions& options,
                                      const std::vector<char>* only) {
  const Eigen::Index n = points.rows();
  std::vector<Outcome> outcome(static_cast<std::size_t>(n));
  PointMatrix c(n, 3), normal(n, 3);
  PointMatrix tet_g;
  if (options.try_tet_gradients) tet_g = tet_gradients(points, values, tri.tets);

  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    auto& out = outcome[std::size_t(i)];
    if (only && !(*only)[std::size_t(i)]) {
      out = Outcome::Skipped;
      return;
    }
    if (tri.hidden[std::size_t(i)]) {
      out = Outcome::Hidden;
      return;
    }
    const Eigen::Vector3d p = row(points, i);
    auto candidate = [&](const Eigen::Vector3d& g) {
      const Eigen::Vector3d unit = g / g.norm();
      const Eigen::Vector3d point = p - values[i] * unit;
      if (inside_neighbour_sphere(points, values, tri, int(i), point, options.tie_tolerance))
        return false;
      c.row(i) = point.transpose();
      normal.row(i) = unit.transpose();
      return true;
    };
    // What is left of a (nearly) covered sphere: a power vertex on it, such as a convex corner.
    auto power_vertex = [&](double tolerance) {
      Eigen::Vector3d at;
      if (!(tolerance > 0) || values[i] == 0 ||
          !power_vertex_point(points, values, tri, int(i), tolerance, at) ||
          inside_neighbour_sphere(points, values, tri, int(i), at, options.tie_tolerance))
        return false;
      c.row(i) = at.transpose();
      normal.row(i) = ((p - at).normalized() * (values[i] > 0 ? 1 : -1)).transpose();
      out = Outcome::Rescued;
      return true;
    };
    const Eigen::Vector3d g = row(gradients, i);
    if (options.max_slope_miss > 0 &&
        misses_linear_prediction(points, values, tri, int(i), g, options.max_slope_miss)) {
      out = Outcome::Discarded;
      power_vertex(options.power_vertex_tolerance);
      return;
    }
    if (!(g.norm() > kTinyGradient)) {
      out = Outcome::ZeroGradient;
    } else {
      out = candidate(g) ? Outcome::Kept : Outcome::Discarded;
    }
    // Where the averaged gradient puts the point (discarded ones only: their g is not zero).
    auto gradient_point = [&] { return Eigen::Vector3d(p - values[i] * g.normalized()); };
    // Pushed out of the spheres it lies in and back onto its own (sphere_slide_rounds).
    auto slide = [&] {
      if (!(options.sphere_slide_rounds > 0) || values[i] == 0) return false;
      const Eigen::Vector3d start = gradient_point();
      const Eigen::Vector3d slid =
          slide_out_of_spheres(points, values, tri, int(i), start, options.sphere_slide_rounds);
      // (Farther than the radius, the gradient said little about where the point lies.)
      if (!slid.allFinite() || (slid - start).norm() > std::abs(values[i]) ||
          inside_neighbour_sphere(points, values, tri, int(i), slid, options.tie_tolerance))
        return false;
      c.row(i) = slid.transpose();
      normal.row(i) = ((p - slid) / values[i]).transpose();
      out = Outcome::Rescued;
      return true;
    };
    if (out == Outcome::Discarded && options.near_miss_tolerance > 0) {
      // Spheres that meet exactly (a corner or edge of exact data) keep their point there, and
      // a slide that finds a free point of the sphere keeps it. Where only an inexact power
      // vertex is left, a candidate discarded by a hair takes its place.
      if (power_vertex(std::min(kExactMeeting, options.power_vertex_tolerance)) || slide()) return;
      if (!power_vertex(options.power_vertex_tolerance)) return;
      const Eigen::Vector3d point = gradient_point();
      if (neighbour_sphere_depth(points, values, tri, int(i), point) <=
          options.near_miss_tolerance * std::abs(values[i])) {
        c.row(i) = point.transpose();
        normal.row(i) = g.normalized().transpose();
      }
      return;
    }
    if (out != Outcome::Kept && power_vertex(options.power_vertex_tolerance)) return;
    if (out == Outcome::Discarded && slide()) return;
    if (out == Outcome::Kept || !options.try_tet_gradients) return;
    for (const int t : tri.incident(int(i))) {
      const Eigen::Vector3d gt = row(tet_g, t);
      if (gt.norm() > kTinyGradient && candidate(gt)) {
        out = Outcome::Rescued;
        return;
      }
    }
  });

  ContactPoints result;
  std::vector<int> kept;
  for (Eigen::Index i = 0; i < n; ++i) {
    switch (outcome[std::size_t(i)]) {
      case Outcome::Skipped:
        break;
      case Outcome::Hidden:
        ++result.hidden;
        break;
      case Outcome::ZeroGradient:
        ++result.zero_gradient;
        break;
      case Outcome::Discarded:
        ++result.discarded;
        break;
      case Outcome::Rescued:
        ++result.rescued;
        kept.push_back(int(i));
        break;
      case Outcome::Kept:
        kept.push_back(int(i));
        break;
    }
  }
  result.samples = kept;
  result.points.resize(Eigen::Index(kept.size()), 3);
  result.normals.resize(Eigen::Index(kept.size()), 3);
  for (std::size_t a = 0; a < kept.size(); ++a) {
    result.points.row(Eigen::Index(a)) = c.row(kept[a]);
    result.normals.row(Eigen::Index(a)) = normal.row(kept[a]);
  }
  return result;
}

ContactPoints exact_contact_points(const PointMatrix& points, const AnalyticShape& shape,
                                   const std::vector<char>* only) {
  ContactPoints result;
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    if (!only || (*only)[std::size_t(i)]) result.samples.push_back(int(i));
  const Eigen::Index n = Eigen::Index(result.samples.size());
  result.points.resize(n, 3);
  result.normals.resize(n, 3);
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index r) {
    const Eigen::Vector3d p = row(points, result.samples[std::size_t(r)]);
    result.points.row(r) = shape.closest_point(p).transpose();
    result.normals.row(r) = shape.gradient(p).transpose();
  });
  return result;
}

}  // namespace sdfcontour
