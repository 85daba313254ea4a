#include "reconstruction/local/cell_quadric.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace sdfcontour::detail {

namespace {

// A direction solved in the first solve stays solved through the reweighting while its eigenvalue
// is above this fraction of feature_ratio times the largest (0.002 for the default 0.02); below,
// the rounds stop.
// On the exact box's edge cells that gather from 2 spacings, a first solve pulled 0.07 h off the
// edge by a few bent normals made the next round judge a whole face an outlier (rank 1, the vertex
// at the other face's centroid, 0.67 h off). Annealing the scale (9, 3, 1 times) instead was
// measured alike on the shared meshes but left bunny and koala samples 0.03-0.05 h on the wrong
// side of the mesh.
constexpr double kKeptRankFraction = 0.1;

// Where an eigenpair misses A by more than this fraction of A's largest eigenvalue, the closed form
// is not trusted: the iterative solver's pairs miss by a few roundings.
constexpr double kDirectMiss = 1e-13;

// A's eigensystem: the closed form (Eigen's computeDirect; the iterative solver was a third of the
// cells' time at 512^3), unless one of the pairs that a solve may take (eigenvalue above
// kKeptRankFraction * feature_ratio of the largest) misses A by more than kDirectMiss. Where two
// eigenvalues repeat (an edge whose faces weigh alike), the closed form's vectors leave their
// space by about 1e-9, which put a solve 1e-10 off its planes
// (CellQuadric.PlanesThroughOnePointAreSolvedExactlyWhenTheirEigenvaluesRepeat).
Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen_3x3(const Eigen::Matrix3d& A,
                                                         double feature_ratio) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(A);
  const Eigen::Vector3d& lambda = eigen.eigenvalues();
  const double largest = std::abs(lambda[2]);
  for (int j = 2; j >= 0; --j) {
    if (!(lambda[j] > kKeptRankFraction * feature_ratio * largest)) break;
    const Eigen::Vector3d v = eigen.eigenvectors().col(j);
    if (!((A * v - lambda[j] * v).cwiseAbs().maxCoeff() <= kDirectMiss * largest)) {
      eigen.compute(A);
      break;
    }
  }
  return eigen;
}

QuadricSolution solve_weighted(const std::vector<TangentPlane>& planes,
                               const std::vector<double>& weight, double feature_ratio,
                               int keep_rank = 0) {
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
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen = eigen_3x3(ata, feature_ratio);
  const Eigen::Vector3d& lambda = eigen.eigenvalues();  // ascending
  QuadricSolution out;
  out.position = centroid;
  for (int j = 2; j >= 0; --j) {
    const double floor = out.rank < keep_rank ? kKeptRankFraction * feature_ratio : feature_ratio;
    if (!(lambda[j] > floor * lambda[2]) || !(lambda[j] > 0)) break;
    const Eigen::Vector3d v = eigen.eigenvectors().col(j);
    out.position += v * (v.dot(atb) / lambda[j]);
    out.free -= v * v.transpose();
    ++out.rank;
  }
  return out;
}

// The planes' own weights.
std::vector<double> given_weights(const std::vector<TangentPlane>& planes) {
  std::vector<double> weight(planes.size());
  for (std::size_t i = 0; i < planes.size(); ++i) weight[i] = planes[i].weight;
  return weight;
}

// A robust round's weights: each plane's own over 1 + (its miss of x / robust_scale)^2.
void reweigh(const std::vector<TangentPlane>& planes, const Eigen::Vector3d& x, double robust_scale,
             std::vector<double>& weight) {
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const double miss = planes[i].normal.dot(x - planes[i].point) / robust_scale;
    weight[i] = planes[i].weight / (1 + miss * miss);
  }
}

// The box-constrained minimiser of sum_i weight_i (n_i . (x - p_i))^2 (minimise_quadric_in_box).
Eigen::Vector3d solve_in_box(const std::vector<TangentPlane>& planes,
                             const std::vector<double>& weight, const Eigen::Vector3d& lo,
                             const Eigen::Vector3d& hi) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double total = 0;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const Eigen::Vector3d& n = planes[i].normal;
    centroid += weight[i] * planes[i].point;
    total += weight[i];
    ata.noalias() += weight[i] * n * n.transpose();
    atb += weight[i] * n * n.dot(planes[i].point);
  }
  const Eigen::Vector3d start = (centroid / total).cwiseMax(lo).cwiseMin(hi);
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(ata).eigenvalues()[2];
  auto value = [&](const Eigen::Vector3d& x) {
    double sum = 0;
    for (std::size_t i = 0; i < planes.size(); ++i) {
      const double r = planes[i].normal.dot(x - planes[i].point);
      sum += weight[i] * r * r;
    }
    return sum;
  };
  Eigen::Vector3d best = start;
  double best_value = value(start);
  const double slack = 1e-12 * (hi - lo).maxCoeff();
  for (int set = 0; set < 27; ++set) {
    // Axis a is free (0), held at lo (1) or at hi (2).
    const int state[3] = {set % 3, set / 3 % 3, set / 9};
    Eigen::Vector3d x = start;
    std::vector<int> free;
    for (int a = 0; a < 3; ++a) {
      if (state[a] == 0) free.push_back(a);
      if (state[a] == 1) x[a] = lo[a];
      if (state[a] == 2) x[a] = hi[a];
    }
    if (!free.empty()) {
      // The free coordinates' normal equations from x, solved along the directions the planes fix.
      const int k = int(free.size());
      Eigen::MatrixXd a(k, k);
      Eigen::VectorXd rhs(k);
      const Eigen::Vector3d gradient = atb - ata * x;
      for (int i = 0; i < k; ++i) {
        rhs[i] = gradient[free[std::size_t(i)]];
        for (int j = 0; j < k; ++j) a(i, j) = ata(free[std::size_t(i)], free[std::size_t(j)]);
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
      Eigen::VectorXd step = Eigen::VectorXd::Zero(k);
      for (int j = 0; j < k; ++j)
        if (eigen.eigenvalues()[j] > 1e-9 * largest) {
          const Eigen::VectorXd v = eigen.eigenvectors().col(j);
          step += v * (v.dot(rhs) / eigen.eigenvalues()[j]);
        }
      for (int i = 0; i < k; ++i) x[free[std::size_t(i)]] += step[i];
    }
    if ((x.array() < lo.array() - slack).any() || (x.array() > hi.array() + slack).any()) continue;
    x = x.cwiseMax(lo).cwiseMin(hi);
    const double v = value(x);
    if (v < best_value) best = x, best_value = v;
  }
  return best;
}

}  // namespace

Eigen::Vector3d minimise_quadric_in_box(const std::vector<TangentPlane>& planes,
                                        const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                        int robust_rounds, double robust_scale) {
  std::vector<double> weight = given_weights(planes);
  Eigen::Vector3d x = solve_in_box(planes, weight, lo, hi);
  for (int round = 0; round < robust_rounds; ++round) {
    reweigh(planes, x, robust_scale, weight);
    x = solve_in_box(planes, weight, lo, hi);
  }
  return x;
}

QuadricSolution minimise_quadric(const std::vector<TangentPlane>& planes, double feature_ratio,
                                 int robust_rounds, double robust_scale) {
  std::vector<double> weight = given_weights(planes);
  QuadricSolution solution = solve_weighted(planes, weight, feature_ratio);
  const int rank = solution.rank;
  for (int round = 0; round < robust_rounds; ++round) {
    reweigh(planes, solution.position, robust_scale, weight);
    // The first solve's rank stays: a whole family of planes (one face of an edge) that a
    // solve pulled by a few bent normals missed must not vanish as outliers, or the feature
    // would become a flat patch at the other face's centroid.
    QuadricSolution next = solve_weighted(planes, weight, feature_ratio, rank);
    if (next.rank < rank) break;  // a curved patch's spread, not a feature's faces
    solution = next;
  }
  return solution;
}

}  // namespace sdfcontour::detail
