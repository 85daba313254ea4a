// Internal: the quadric error of a cell's tangent planes and its rank-truncated, robust minimiser.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace sdfcontour::detail {

/// A tangent plane: a point on it, its unit normal and its weight (how much it is trusted).
struct TangentPlane {
  Eigen::Vector3d point, normal;
  double weight = 1;
};

struct QuadricSolution {
  Eigen::Vector3d position;
  int rank = 0;  ///< directions solved for: 1 a plane, 2 an edge, 3 a corner
  /// The projector onto the directions not solved for (along which every point of
  /// `position` + free * d minimises the quadric as well).
  Eigen::Matrix3d free = Eigen::Matrix3d::Identity();
};

/// The point that minimises sum_i w_i (n_i . (x - p_i))^2 over `planes` (not empty), solving only
/// for directions whose eigenvalue of sum w_i n_i n_i^T exceeds `feature_ratio` times the largest
/// and keeping the planes' weighted centroid along the others. `robust_rounds` reweightings follow
/// (w_i = weight_i / (1 + (r_i / robust_scale)^2) for the plane's miss r_i; robust_scale is a
/// length), so that planes that disagree with the rest lose their pull. The reweighted solves
/// keep the first solve's directions while their eigenvalues exceed a tenth of `feature_ratio`
/// (a whole face of an edge is not judged an outlier); a round that would lose one is not taken.
QuadricSolution minimise_quadric(const std::vector<TangentPlane>& planes, double feature_ratio,
                                 int robust_rounds, double robust_scale);

/// The point of the box [lo, hi] that minimises the same quadric (planes not empty), with
/// `robust_rounds` reweightings as above. Every face, edge and corner of the box is tried as the
/// set of active bounds (27 sets) and the least value among the feasible solutions is taken;
/// directions that no plane fixes (eigenvalues under 1e-9 of the largest) keep the planes'
/// weighted centroid, clamped into the box.
Eigen::Vector3d minimise_quadric_in_box(const std::vector<TangentPlane>& planes,
                                        const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                        int robust_rounds, double robust_scale);

}  // namespace sdfcontour::detail
