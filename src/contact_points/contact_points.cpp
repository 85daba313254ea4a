#include "sdfcontour/contact_points/contact_points.h"

#include <tbb/parallel_for.h>

#include <cmath>

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

bool inside_neighbour_sphere(const PointMatrix& points, const Eigen::VectorXd& values,
                             const Triangulation& tri, int i, const Eigen::Vector3d& c,
                             double tau) {
  const Eigen::Vector3d p = row(points, i);
  for (int o = tri.neighbour_offsets[std::size_t(i)]; o < tri.neighbour_offsets[std::size_t(i) + 1];
       ++o) {
    const int j = tri.neighbour_indices[std::size_t(o)];
    const Eigen::Vector3d q = row(points, j);
    const double radius = std::abs(values[j]) - (tau > 0 ? tau * (q - p).norm() : 0.0);
    if (radius > 0 && (c - q).squaredNorm() < radius * radius) return true;
  }
  return false;
}

namespace {

// Whether a triangulation neighbour of sample i misses the linear prediction from gradient g by
// more than `slope` times its distance.
bool misses_linear_prediction(const PointMatrix& points, const Eigen::VectorXd& values,
                              const Triangulation& tri, int i, const Eigen::Vector3d& g,
                              double slope) {
  const Eigen::Vector3d p = row(points, i);
  for (int o = tri.neighbour_offsets[std::size_t(i)]; o < tri.neighbour_offsets[std::size_t(i) + 1];
       ++o) {
    const int j = tri.neighbour_indices[std::size_t(o)];
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
    for (int o = tri.neighbour_offsets[std::size_t(i)];
         o < tri.neighbour_offsets[std::size_t(i) + 1]; ++o) {
      const int j = tri.neighbour_indices[std::size_t(o)];
      const Eigen::Vector3d away = c - row(points, j);
      const double depth = std::abs(values[j]) - away.norm();
      if (depth > 0 && away.norm() > 0) push += depth * away.normalized();
    }
    if (push.squaredNorm() == 0) break;
    c = p + radius * (c + push - p).normalized();
  }
  return c;
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
    const Eigen::Vector3d g = row(gradients, i);
    if (options.max_slope_miss > 0 &&
        misses_linear_prediction(points, values, tri, int(i), g, options.max_slope_miss)) {
      out = Outcome::Discarded;
      return;
    }
    if (!(g.norm() > kTinyGradient)) {
      out = Outcome::ZeroGradient;
    } else {
      out = candidate(g) ? Outcome::Kept : Outcome::Discarded;
    }
    if (out == Outcome::Discarded && options.sphere_slide_rounds > 0 && values[i] != 0) {
      const Eigen::Vector3d start = p - values[i] * g.normalized();
      const Eigen::Vector3d slid =
          slide_out_of_spheres(points, values, tri, int(i), start, options.sphere_slide_rounds);
      // (Farther than the radius, the gradient said little about where the point lies.)
      if (slid.allFinite() && (slid - start).norm() <= std::abs(values[i]) &&
          !inside_neighbour_sphere(points, values, tri, int(i), slid, options.tie_tolerance)) {
        c.row(i) = slid.transpose();
        normal.row(i) = ((p - slid) / values[i]).transpose();
        out = Outcome::Rescued;
        return;
      }
    }
    if (out == Outcome::Kept || !options.try_tet_gradients) return;
    for (int o = tri.incident_offsets[std::size_t(i)]; o < tri.incident_offsets[std::size_t(i) + 1];
         ++o) {
      const Eigen::Vector3d gt = row(tet_g, tri.incident_tets[std::size_t(o)]);
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
