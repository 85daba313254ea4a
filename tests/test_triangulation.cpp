#include <Eigen/Dense>

#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "test_support.h"

using namespace sdfcontour;
using Eigen::Vector3d;

namespace {

// The orthogonal sphere of tet t (centre, squared radius) for weights w: the sphere whose power
// distance to each of the four weighted vertices is zero.
std::pair<Vector3d, double> orthosphere(const PointMatrix& p, const Eigen::VectorXd& w,
                                        const TetMatrix& tets, Eigen::Index t) {
  Eigen::Matrix3d A;
  Eigen::Vector3d b;
  const Vector3d p0 = p.row(tets(t, 0));
  for (int k = 1; k < 4; ++k) {
    const Vector3d pk = p.row(tets(t, k));
    A.row(k - 1) = 2 * (pk - p0).transpose();
    b[k - 1] = pk.squaredNorm() - p0.squaredNorm() - (w[tets(t, k)] - w[tets(t, 0)]);
  }
  const Vector3d x = A.fullPivLu().solve(b);
  return {x, (x - p0).squaredNorm() - w[tets(t, 0)]};
}

// Checks that no sample lies strictly inside (in conflict with) any tet's orthosphere, which is
// the defining property of the weighted (or, with zero weights, plain) Delaunay triangulation.
void expect_empty_orthospheres(const PointMatrix& p, const Eigen::VectorXd& weights,
                               const Triangulation& tri) {
  int violations = 0;
  for (Eigen::Index t = 0; t < tri.tets.rows(); ++t) {
    const auto [x, r2] = orthosphere(p, weights, tri.tets, t);
    for (Eigen::Index q = 0; q < p.rows(); ++q)
      if ((x - Vector3d(p.row(q))).squaredNorm() - weights[q] < r2 - 1e-9) ++violations;
  }
  EXPECT_EQ(violations, 0);
}

void expect_consistent(const Triangulation& tri, const PointMatrix& p) {
  const int n = int(p.rows());
  ASSERT_EQ(tri.sample_count(), n);
  std::vector<char> used(std::size_t(n), 0);
  const Eigen::VectorXd vol = tet_volumes(p, tri.tets);
  for (Eigen::Index t = 0; t < tri.tets.rows(); ++t) {
    EXPECT_GT(vol[t], 0) << "tet " << t << " is not positively oriented";
    for (int k = 0; k < 4; ++k) used[std::size_t(tri.tets(t, k))] = 1;
  }
  int hidden = 0;
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(bool(tri.hidden[std::size_t(i)]), !used[std::size_t(i)]) << "sample " << i;
    hidden += tri.hidden[std::size_t(i)];
  }
  EXPECT_EQ(hidden, tri.hidden_count);
  // Neighbour lists are symmetric.
  for (int i = 0; i < n; ++i)
    for (int o = tri.neighbour_offsets[std::size_t(i)];
         o < tri.neighbour_offsets[std::size_t(i) + 1]; ++o) {
      const int j = tri.neighbour_indices[std::size_t(o)];
      const auto b = tri.neighbour_indices.begin() + tri.neighbour_offsets[std::size_t(j)],
                 e = tri.neighbour_indices.begin() + tri.neighbour_offsets[std::size_t(j) + 1];
      EXPECT_TRUE(std::binary_search(b, e, i));
    }
}

}  // namespace

TEST(Triangulation, DelaunayHasEmptyCircumspheres) {
  const PointMatrix p = test::random_points(300, 1);
  const Eigen::VectorXd values = Eigen::VectorXd::Random(300);
  const Triangulation tri = triangulate(p, values, {TriangulationKind::Delaunay, true});
  expect_consistent(tri, p);
  EXPECT_EQ(tri.hidden_count, 0);
  expect_empty_orthospheres(p, Eigen::VectorXd::Zero(300), tri);
}

TEST(Triangulation, RegularHasEmptyOrthospheresAndHiddenSamples) {
  const PointMatrix p = test::random_points(400, 2);
  Eigen::VectorXd values = 0.25 * Eigen::VectorXd::Random(400);
  const Triangulation tri = triangulate(p, values, {TriangulationKind::Regular, true});
  expect_consistent(tri, p);
  EXPECT_GT(tri.hidden_count, 0);  // large random spheres hide some samples
  expect_empty_orthospheres(p, values.cwiseProduct(values), tri);
}

TEST(Triangulation, GridTetsFillTheBox) {
  const auto shape = make_builtin_shape("torus");
  const Grid g = sample_grid(*shape, 12, Bounds{});
  const Samples s = g.to_samples();
  for (auto kind : {TriangulationKind::Regular, TriangulationKind::Delaunay}) {
    const Triangulation tri = triangulate(s.points, s.values, {kind, true});
    expect_consistent(tri, s.points);
    EXPECT_NEAR(tet_volumes(s.points, tri.tets).sum(), 8.0, 1e-9);
  }
}

TEST(Triangulation, SameResultWhateverTheThreads) {
  for (const std::string name : {"box", "torus"}) {
    const auto shape = make_builtin_shape(name);
    const Samples s = sample_grid(*shape, 20, Bounds{}).to_samples();
    for (auto kind : {TriangulationKind::Regular, TriangulationKind::Delaunay}) {
      const Triangulation serial = triangulate(s.points, s.values, {kind, false});
      const Triangulation parallel = triangulate(s.points, s.values, {kind, true});
      EXPECT_EQ(serial.tets, parallel.tets) << name;
      EXPECT_EQ(serial.hidden, parallel.hidden) << name;
    }
  }
}

TEST(Triangulation, RejectsDegenerateInput) {
  PointMatrix flat = test::random_points(50, 4);
  flat.col(2).setConstant(0.3);
  EXPECT_THROW(triangulate(flat, Eigen::VectorXd::Ones(50), {}), Error);
  PointMatrix line(10, 3);
  for (int i = 0; i < 10; ++i) line.row(i) << i, 2 * i, 3 * i;
  EXPECT_THROW(triangulate(line, Eigen::VectorXd::Ones(10), {}), Error);
  EXPECT_THROW(triangulate(test::random_points(3, 1), Eigen::VectorXd::Ones(3), {}), Error);
}

TEST(Triangulation, DuplicatePositionsAreHidden) {
  PointMatrix p = test::random_points(40, 9);
  p.row(39) = p.row(3);
  const Triangulation tri =
      triangulate(p, Eigen::VectorXd::Zero(40), {TriangulationKind::Delaunay, true});
  EXPECT_EQ(tri.hidden_count, 1);
  EXPECT_TRUE(tri.hidden[3] || tri.hidden[39]);
}
