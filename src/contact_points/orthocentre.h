// The point of equal power to four weighted samples (their spheres' radical centre).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <utility>

namespace sdfcontour::detail {

/// The orthocentre of four samples at `points` with values `values` (weights value^2), and its
/// power (the same to all four). The samples are taken in position order, so that any order of
/// them, in any brick, gives the same bits. Returns false where the four lie on a plane (the
/// centre is then the solver's least answer).
inline bool orthocentre(std::array<std::pair<Eigen::Vector3d, double>, 4> samples,
                        Eigen::Vector3d& centre, double& power) {
  std::sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) {
    return std::lexicographical_compare(a.first.data(), a.first.data() + 3, b.first.data(),
                                        b.first.data() + 3);
  });
  const Eigen::Vector3d p0 = samples[0].first;
  const double w0 = samples[0].second * samples[0].second;
  Eigen::Matrix3d a;
  Eigen::Vector3d b;
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d d = samples[std::size_t(j) + 1].first - p0;
    const double wj = samples[std::size_t(j) + 1].second * samples[std::size_t(j) + 1].second;
    a.row(j) = 2 * d.transpose();
    b[j] = d.squaredNorm() - (wj - w0);
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(a);
  const Eigen::Vector3d y = lu.solve(b);
  centre = p0 + y;
  power = y.squaredNorm() - w0;
  return lu.isInvertible();
}

}  // namespace sdfcontour::detail
