// Built-in analytic shapes with exact signed distances and exact gradients: the embedded
// examples and the test fixtures. Their gradients give ground-truth contact points (GTCP).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sdfcontour/samples.h"

namespace sdfcontour {

/// A shape with an exact signed distance function (negative inside).
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

/// Names of the built-in shapes: sphere, torus, box, plate, shell, csg.
std::vector<std::string> builtin_shape_names();

/// The built-in shape `name`; throws Error for an unknown name.
///  - sphere: radius 0.6 at the origin.
///  - torus: major radius 0.55, minor radius 0.25, around the z axis.
///  - box: half-extents (0.6, 0.45, 0.35), sharp edges and corners.
///  - plate: a thin box, half-extents (0.7, 0.5, 0.06).
///  - shell: a hollow sphere, radii 0.55 and 0.65 (a thin shell, two sheets).
///  - csg: union of two overlapping spheres, with a concave crease circle where they meet.
std::unique_ptr<AnalyticShape> make_builtin_shape(const std::string& name);

/// A parsed `builtin:NAME@N` (an N^3 grid) or `builtin:NAME@random:COUNT` specification.
struct BuiltinSpec {
  std::string name;
  bool random = false;
  int resolution = 0;     ///< grid samples per axis, when !random
  std::size_t count = 0;  ///< number of random samples, when random
};

/// True if `text` starts with "builtin:".
bool is_builtin_spec(const std::string& text);
/// Parses a built-in specification; throws Error naming what is wrong.
BuiltinSpec parse_builtin_spec(const std::string& text);

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
