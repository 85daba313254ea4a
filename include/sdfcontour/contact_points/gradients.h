// Approximate SDF gradients at the samples: from the piecewise-linear interpolant on a
// triangulation (averaged over each sample's incident tetrahedra), or by least squares over the
// k nearest neighbours.
#pragma once

#include <string>
#include <vector>

#include "sdfcontour/contact_points/triangulation.h"

namespace sdfcontour {

enum class GradientWeighting {
  Uniform,  ///< w_t = 1
  Volume,   ///< w_t = volume of tet t
  James,    ///< James (2020, Phong deformation) weights: the weighted tet centroids reproduce p
};

/// "uniform", "volume", "james" <-> GradientWeighting; parse throws Error for other names.
GradientWeighting parse_gradient_weighting(const std::string& name);
std::string gradient_weighting_name(GradientWeighting weighting);

struct GradientOptions {
  GradientWeighting weighting = GradientWeighting::James;
  /// Regularisation of the James system (eps*I + sum r r^T) lambda = -sum r. With eps -> 0 the
  /// weights have linear precision (sum_t w_t (c_t - p) = 0); eps keeps samples with few or
  /// one-sided tets well posed. 0.1 keeps 5-8% more GCP contact points than 1 (the value in
  /// public implementations), with lower median error (bench/contact_points.py, README).
  double james_epsilon = 0.1;
};

/// Gradient of the linear interpolant of `values` on each tet (m x 3). `degenerate` receives one
/// flag per tet: 1 where the tet is too flat for a gradient (its row is then zero). `wanted`
/// (optional, one flag per tet): only those tets are computed, the other rows are zero.
PointMatrix tet_gradients(const PointMatrix& points, const Eigen::VectorXd& values,
                          const TetMatrix& tets, std::vector<char>* degenerate = nullptr,
                          const std::vector<char>* wanted = nullptr);

/// Signed volume of each tet (m); positive for positively oriented tets.
Eigen::VectorXd tet_volumes(const PointMatrix& points, const TetMatrix& tets);

/// James weights for one sample at p whose incident tets have `centroids` (k x 3): one weight per
/// tet, w_t = (1 + lambda . r_t/|r_t|) / |r_t| with r_t = c_t - p and
/// (eps I + sum r^ r^T) lambda = -sum r^.
Eigen::VectorXd james_weights(const Eigen::Vector3d& p, const PointMatrix& centroids,
                              double epsilon);

/// Per-sample gradients (n x 3): the weighted average of the incident tets' gradients.
/// Samples without a (non-degenerate) incident tet, hidden ones say, get a zero row; so do
/// samples not flagged in `only` (n flags), when given.
PointMatrix vertex_gradients(const PointMatrix& points, const Eigen::VectorXd& values,
                             const Triangulation& triangulation,
                             const GradientOptions& options = {},
                             const std::vector<char>* only = nullptr);

/// Per-sample gradients (n x 3) of the linear function that interpolates the sample and fits its
/// k nearest neighbours in the least-squares sense (the paper uses k = 6, 18, 26).
PointMatrix knn_gradients(const PointMatrix& points, const Eigen::VectorXd& values, int k);

}  // namespace sdfcontour
