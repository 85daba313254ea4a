#include "sdfcontour/contact_points/gradients.h"
#include "test_support.h"

using namespace sdfcontour;
using Eigen::Vector3d;

namespace {

const Vector3d kSlope(0.3, -1.7, 0.9);

Eigen::VectorXd linear_field(const PointMatrix& p) {
  return (p * kSlope).array() + 0.2;  // 0.2 offset: a sign change near the middle
}

// Largest relative error of the visible samples' gradients against kSlope.
double worst_relative_error(const PointMatrix& g, const std::vector<char>& hidden) {
  double worst = 0;
  for (Eigen::Index i = 0; i < g.rows(); ++i)
    if (!hidden[std::size_t(i)])
      worst = std::max(worst, (Vector3d(g.row(i)) - kSlope).norm() / kSlope.norm());
  return worst;
}

struct Case {
  std::string name;
  PointMatrix points;
};

std::vector<Case> cases() {
  return {{"grid", test::grid_points(10)}, {"random", test::random_points(600, 5)}};
}

}  // namespace

TEST(Gradients, ExactOnLinearFieldsForEveryWeighting) {
  for (const Case& c : cases()) {
    const Eigen::VectorXd f = linear_field(c.points);
    for (auto kind : {TriangulationKind::Regular, TriangulationKind::Delaunay}) {
      const Triangulation tri = triangulate(c.points, f, {kind, true});
      for (auto w :
           {GradientWeighting::Uniform, GradientWeighting::Volume, GradientWeighting::James}) {
        SCOPED_TRACE(c.name + (kind == TriangulationKind::Regular ? " regular " : " delaunay ") +
                     std::to_string(int(w)));
        const PointMatrix g = vertex_gradients(c.points, f, tri, {w, 1.0});
        EXPECT_LT(worst_relative_error(g, tri.hidden), 1e-9);
      }
    }
    for (int k : {6, 18, 26}) {
      SCOPED_TRACE(c.name + " knn " + std::to_string(k));
      const PointMatrix g = knn_gradients(c.points, f, k);
      EXPECT_LT(worst_relative_error(g, std::vector<char>(std::size_t(c.points.rows()), 0)), 1e-9);
    }
  }
}

TEST(Gradients, TetGradientsInterpolateTheVertexValues) {
  const PointMatrix p = test::random_points(200, 8);
  const Eigen::VectorXd f = Eigen::VectorXd::Random(200);
  const Triangulation tri = triangulate(p, f, {TriangulationKind::Delaunay, true});
  const PointMatrix g = tet_gradients(p, f, tri.tets);
  for (Eigen::Index t = 0; t < tri.tets.rows(); ++t)
    for (int k = 1; k < 4; ++k) {
      const Vector3d e = p.row(tri.tets(t, k)) - p.row(tri.tets(t, 0));
      EXPECT_NEAR(Vector3d(g.row(t)).dot(e), f[tri.tets(t, k)] - f[tri.tets(t, 0)], 1e-9);
    }
}

// James's weights are built so that the weighted tet centroids reproduce the vertex,
// sum_t w_t (c_t - p) = 0 (linear precision). Solving (eps I + M) lambda = -sum r^ gives
// sum_t w_t (c_t - p) = -eps lambda, so the property holds as eps -> 0 and only approximately at
// eps = 1.
TEST(Gradients, JamesWeightsHaveLinearPrecision) {
  const PointMatrix p = test::random_points(500, 21);
  const Triangulation tri =
      triangulate(p, Eigen::VectorXd::Zero(500), {TriangulationKind::Delaunay, true});
  double worst_small_eps = 0, worst_eps_one = 0;
  for (int i = 0; i < 500; ++i) {
    const int begin = tri.incident_offsets[std::size_t(i)],
              end = tri.incident_offsets[std::size_t(i) + 1];
    PointMatrix centroids(end - begin, 3);
    for (int o = begin; o < end; ++o) {
      Vector3d c = Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        c += p.row(tri.tets(tri.incident_tets[std::size_t(o)], k)).transpose();
      centroids.row(o - begin) = c.transpose() / 4;
    }
    const Vector3d pi = p.row(i);
    for (double eps : {1e-10, 1.0}) {
      const Eigen::VectorXd w = james_weights(pi, centroids, eps);
      Vector3d moment = Vector3d::Zero();
      double scale = 0;
      for (Eigen::Index t = 0; t < w.size(); ++t) {
        moment += w[t] * (Vector3d(centroids.row(t)) - pi);
        scale += std::abs(w[t]) * (Vector3d(centroids.row(t)) - pi).norm();
      }
      (eps < 1 ? worst_small_eps : worst_eps_one) =
          std::max(eps < 1 ? worst_small_eps : worst_eps_one, moment.norm() / scale);
    }
  }
  EXPECT_LT(worst_small_eps, 1e-6);
  EXPECT_GT(worst_eps_one, 1e-3);  // eps = 1 trades exactness for robustness
}

// The point of linear precision: on a quadratic field, where each tet's gradient is (nearly) the
// true gradient at its centroid, James's average is more accurate than a uniform one.
TEST(Gradients, JamesBeatsUniformOnQuadraticFields) {
  const PointMatrix p = test::random_points(3000, 13);
  Eigen::VectorXd f(p.rows());
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    f[i] = Vector3d(p.row(i)).squaredNorm() - 0.4;  // grad = 2p
  const Triangulation tri = triangulate(p, f, {TriangulationKind::Delaunay, true});
  auto mean_error = [&](GradientWeighting w, double eps) {
    const PointMatrix g = vertex_gradients(p, f, tri, {w, eps});
    double sum = 0;
    int count = 0;
    for (Eigen::Index i = 0; i < p.rows(); ++i)
      if (Vector3d(p.row(i)).cwiseAbs().maxCoeff() < 0.8) {  // interior samples
        sum += (Vector3d(g.row(i)) - 2 * Vector3d(p.row(i))).norm();
        ++count;
      }
    return sum / count;
  };
  const double uniform = mean_error(GradientWeighting::Uniform, 1.0);
  const double james_exact = mean_error(GradientWeighting::James, 1e-10);
  const double james_default = mean_error(GradientWeighting::James, 1.0);
  std::cout << "mean gradient error on x^2+y^2+z^2: uniform " << uniform << ", volume "
            << mean_error(GradientWeighting::Volume, 1.0) << ", james(eps=1e-10) " << james_exact
            << ", james(eps=1) " << james_default << "\n";
  EXPECT_LT(james_exact, uniform);
  EXPECT_LT(james_default, uniform);
}
