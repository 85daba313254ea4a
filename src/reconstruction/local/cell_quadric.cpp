#include "reconstruction/local/cell_quadric.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace sdfcontour::detail {

namespace {

QuadricSolution solve_weighted(const std::vector<TangentPlane>& planes,
                               const std::vector<double>& weight, double feature_ratio) {
  // Centred on the weighted centroid: the minimiser moves from it only along solved directions.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double total = 0;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    centroid += weight[i] * planes[i].point;
    total += weight[i];
  }
  centroid /= total;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const Eigen::Vector3d& n = planes[i].normal;
    ata.noalias() += weight[i] * n * n.transpose();
    atb += weight[i] * n * n.dot(planes[i].point - centroid);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(ata);
  const Eigen::Vector3d& lambda = eigen.eigenvalues();  // ascending
  QuadricSolution out;
  out.position = centroid;
  for (int j = 2; j >= 0; --j) {
    if (!(lambda[j] > feature_ratio * lambda[2]) || !(lambda[j] > 0)) break;
    const Eigen::Vector3d v = eigen.eigenvectors().col(j);
    out.position += v * (v.dot(atb) / lambda[j]);
    out.free -= v * v.transpose();
    ++out.rank;
  }
  return out;
}

}  // namespace

QuadricSolution minimise_quadric(const std::vector<TangentPlane>& planes, double feature_ratio,
                                 int robust_rounds, double robust_scale) {
  std::vector<double> weight(planes.size());
  for (std::size_t i = 0; i < planes.size(); ++i) weight[i] = planes[i].weight;
  QuadricSolution solution = solve_weighted(planes, weight, feature_ratio);
  for (int round = 0; round < robust_rounds; ++round) {
    for (std::size_t i = 0; i < planes.size(); ++i) {
      const double miss = planes[i].normal.dot(solution.position - planes[i].point) / robust_scale;
      weight[i] = planes[i].weight / (1 + miss * miss);
    }
    solution = solve_weighted(planes, weight, feature_ratio);
  }
  return solution;
}

}  // namespace sdfcontour::detail
