// The samples just outside a brick's box (internal). A tet's orthosphere that reaches out of the
// box is still a global one if no actual sample out there conflicts with it; testing those
// samples, rather than bounding every outside weight by the largest, lets bricks keep thin halos.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "contact_points/brick_geometry.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour {

class BrickShell {
 public:
  /// No shell: only spheres inside the box itself are certified.
  BrickShell() = default;
  /// The samples `rows` of `points` (n x 3) and `values` (n) that lie in `outer` but outside the
  /// brick's box, bucketed in cubes of side about `cell` (coarser for a large box, so that the
  /// buckets stay few).
  BrickShell(const PointMatrix& points, const Eigen::VectorXd& values, const std::vector<int>& rows,
             const BrickBox& outer, double cell);

  /// The box beyond which no sample is known: spheres must stay inside it.
  const BrickBox& outer() const { return outer_; }
  bool empty() const { return samples_.empty(); }

  /// True if no shell sample q conflicts with the sphere about c of squared radius r2 (which may
  /// be negative): |c - q|^2 - w_q < r2, w_q = value_q^2, taken with a `margin` of rounding, so
  /// a near tie counts as a conflict. Only samples within `reach` of c are looked at: the
  /// caller's bound on sqrt(r2 + w_q) + margin.
  bool conflict_free(const Eigen::Vector3d& c, double r2, double reach, double margin) const;

 private:
  BrickBox outer_{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double cell_ = 1;
  std::array<int, 3> dims_{0, 0, 0};
  std::vector<int> offsets_;              // bucket b's samples are [offsets_[b], offsets_[b + 1])
  std::vector<Eigen::Vector4d> samples_;  // x, y, z, weight, bucket by bucket
};

}  // namespace sdfcontour
