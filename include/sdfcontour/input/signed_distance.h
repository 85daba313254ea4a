// The signed-distance interface (a function that can be evaluated anywhere, with its gradient)
// and the samplers that turn one into the samples the contouring methods take.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// A signed distance function (negative inside) with its gradient: the built-in shapes, a
/// closed mesh (MeshSdf).
class AnalyticShape {
 public:
  virtual ~AnalyticShape() = default;
  /// Exact signed distance at p.
  virtual double distance(const Eigen::Vector3d& p) const = 0;
  /// Exact unit gradient of the signed distance at p (one valid choice on the medial axis).
  virtual Eigen::Vector3d gradient(const Eigen::Vector3d& p) const = 0;
  /// The closest surface point to p: p - distance(p) * gradient(p).
  Eigen::Vector3d closest_point(const Eigen::Vector3d& p) const {
    return p - distance(p) * gradient(p);
  }
};

/// Samples `shape` on an n^3 grid spanning `bounds` (samples at both ends).
Grid sample_grid(const AnalyticShape& shape, int n, const Bounds& bounds);
/// A truncated SDF of `shape` on an n^3 grid: the distance where |distance| < truncation, and
/// +-truncation elsewhere, as TSDF fusion and OpenVDB store it. The distance is 1-Lipschitz, so
/// an 8^3 block whose centre is farther than truncation + its half-diagonal from the surface is
/// filled without evaluating its samples: the cost follows the surface, not n^3. `evaluations`
/// (optional) receives the number of distance evaluations.
Grid sample_grid_truncated(const AnalyticShape& shape, int n, const Bounds& bounds,
                           double truncation, std::size_t* evaluations = nullptr);

/// Samples `shape` at `count` points uniformly distributed in `bounds`; deterministic in `seed`.
Samples sample_random(const AnalyticShape& shape, std::size_t count, const Bounds& bounds,
                      std::uint64_t seed);

}  // namespace sdfcontour
