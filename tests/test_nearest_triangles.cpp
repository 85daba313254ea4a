// Nearest-triangle and ball queries over chunked trees (nearest_triangles.h) against a
// brute-force scan.
#include <CGAL/Simple_cartesian.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>

#include "reconstruction/nearest_triangles.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

using K = CGAL::Simple_cartesian<double>;

// m small random triangles in [-1, 1]^3: enough of them for several chunks.
Mesh random_triangles(int m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> where(-1, 1), offset(-0.02, 0.02);
  Mesh mesh;
  mesh.vertices.resize(3 * m, 3);
  mesh.triangles.resize(m, 3);
  for (int t = 0; t < m; ++t) {
    const Eigen::RowVector3d c(where(rng), where(rng), where(rng));
    for (int k = 0; k < 3; ++k) {
      mesh.vertices.row(3 * t + k) = c + Eigen::RowVector3d(offset(rng), offset(rng), offset(rng));
      mesh.triangles(t, k) = 3 * t + k;
    }
  }
  return mesh;
}

double squared_distance(const Mesh& mesh, int t, const Eigen::Vector3d& p) {
  auto point = [&](int c) {
    const auto v = mesh.vertices.row(mesh.triangles(t, c));
    return K::Point_3(v[0], v[1], v[2]);
  };
  return CGAL::squared_distance(K::Point_3(p[0], p[1], p[2]),
                                K::Triangle_3(point(0), point(1), point(2)));
}

// Every query's nearest triangle and ball tests against a brute-force scan, over all of the
// mesh's triangles and over a third of them.
void expect_brute_force_answers(const Mesh& mesh, const PointMatrix& queries) {
  std::vector<int> among;
  for (int t = 0; t < mesh.triangles.rows(); t += 3) among.push_back(t);
  const std::vector<int>* subsets[] = {nullptr, &among};
  for (const std::vector<int>* subset : subsets) {
    const detail::NearestTriangles tree(mesh, subset, true);
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      const Eigen::Vector3d p = queries.row(q).transpose();
      double best = INFINITY;
      const int count = subset ? int(subset->size()) : int(mesh.triangles.rows());
      for (int i = 0; i < count; ++i)
        best = std::min(best, squared_distance(mesh, subset ? (*subset)[std::size_t(i)] : i, p));
      const detail::NearestTriangles::Hit hit = tree.closest(p);
      ASSERT_GE(hit.triangle, 0);
      if (subset) {
        EXPECT_EQ(hit.triangle % 3, 0) << "a triangle outside the subset";
      }
      EXPECT_NEAR(squared_distance(mesh, hit.triangle, p), best, 1e-15);
      EXPECT_NEAR((hit.point - p).squaredNorm(), best, 1e-12);
      EXPECT_TRUE(tree.meets_ball(p, std::sqrt(best) * 1.001 + 1e-12));
      EXPECT_FALSE(tree.meets_ball(p, std::sqrt(best) * 0.999));
    }
  }
}

}  // namespace

// Triangles of alike sizes: the uniform grid.
TEST(NearestTriangles, AgreesWithABruteForceScan) {
  const Mesh mesh = random_triangles(100000, 3);
  expect_brute_force_answers(mesh, test::random_points(150, 11) * 1.2);  // some outside
}

// One triangle 100 times the others' size: CGAL's trees (4 chunks).
TEST(NearestTriangles, AgreesWithABruteForceScanOverUnlikeSizes) {
  Mesh mesh = random_triangles(100000, 3);
  mesh.vertices.row(3) << -1, -1, 0.3;
  mesh.vertices.row(4) << 1, -1, 0.3;
  mesh.vertices.row(5) << 0, 1, 0.35;
  expect_brute_force_answers(mesh, test::random_points(150, 11) * 1.2);
}

// Degenerate triangles (a segment, a point) among the others: their nearest points are on
// their edges.
TEST(NearestTriangles, DegenerateTrianglesAsTheirEdges) {
  Mesh mesh = random_triangles(2000, 9);
  mesh.vertices.row(0) << 0, 0, 0;
  mesh.vertices.row(1) << 0.01, 0.01, 0;
  mesh.vertices.row(2) << 0.02, 0.02, 0;  // collinear
  mesh.vertices.row(3) << 0.5, 0.5, 0.5;
  mesh.vertices.row(4) << 0.5, 0.5, 0.5;
  mesh.vertices.row(5) << 0.5, 0.5, 0.5;  // one point
  const detail::NearestTriangles tree(mesh, nullptr, false);
  const auto hit = tree.closest(Eigen::Vector3d(0.02, 0.005, 0.001));
  ASSERT_EQ(hit.triangle, 0);
  EXPECT_NEAR((hit.point - Eigen::Vector3d(0.0125, 0.0125, 0)).norm(), 0, 1e-15);
  const auto at_point = tree.closest(Eigen::Vector3d(0.5, 0.5, 0.5001));
  ASSERT_EQ(at_point.triangle, 1);
  EXPECT_NEAR((at_point.point - Eigen::Vector3d(0.5, 0.5, 0.5)).norm(), 0, 1e-15);
}

// A surface of like triangles and queries near it, many straight over its vertices, whose nearest
// point several triangles share: each answer is the least distance's least index, as the scan
// finds it with the same projection (the rings read cell by cell, nearest first).
TEST(NearestTriangles, NearASurfaceTheLeastIndexAmongTies) {
  constexpr int n = 60;
  Mesh mesh;
  mesh.vertices.resize(n * n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = -1 + 2.0 * i / (n - 1), y = -1 + 2.0 * j / (n - 1);
      mesh.vertices.row(i * n + j) << x, y, 0.2 * std::sin(3 * x) * std::cos(2 * y);
    }
  mesh.triangles.resize(2 * (n - 1) * (n - 1), 3);
  int t = 0;
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      const int a = i * n + j, b = a + n, c = a + 1, d = b + 1;
      mesh.triangles.row(t++) << a, b, d;
      mesh.triangles.row(t++) << a, d, c;
    }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::uniform_int_distribution<int> vertex(0, n * n - 1);
  PointMatrix queries(600, 3);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Eigen::RowVector3d up(0, 0, 0.02 * unit(rng));
    queries.row(q) = q % 2 ? mesh.vertices.row(vertex(rng)) + up
                           : Eigen::RowVector3d(unit(rng), unit(rng), 0.25 * unit(rng));
  }
  auto projected = [&](int f, const Eigen::Vector3d& p) {
    auto point = [&](int c) {
      const auto v = mesh.vertices.row(mesh.triangles(f, c));
      return K::Point_3(v[0], v[1], v[2]);
    };
    const K::Point_3 x = K().construct_projected_point_3_object()(
        K::Triangle_3(point(0), point(1), point(2)), K::Point_3(p[0], p[1], p[2]));
    return (Eigen::Vector3d(x.x(), x.y(), x.z()) - p).squaredNorm();
  };
  const detail::NearestTriangles tree(mesh, nullptr, true);
  int ties = 0;
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Eigen::Vector3d p = queries.row(q).transpose();
    double best = INFINITY;
    int first = -1, tied = 0;
    for (int f = 0; f < mesh.triangles.rows(); ++f) {
      const double d = projected(f, p);
      if (d < best)
        best = d, first = f, tied = 1;
      else if (d == best)
        ++tied;
    }
    ties += tied > 1;
    ASSERT_EQ(tree.closest(p).triangle, first) << "query " << q;
  }
  EXPECT_GT(ties, 5);  // (exact ties: the projections round alike onto a shared vertex)
}

TEST(NearestTriangles, TheSameAnswerForAnyThreadCount) {
  const Mesh mesh = random_triangles(70000, 5);
  const PointMatrix queries = test::random_points(400, 7);
  std::vector<int> found[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const detail::NearestTriangles tree(mesh, nullptr, threads == 2);
    for (Eigen::Index q = 0; q < queries.rows(); ++q)
      found[threads - 1].push_back(tree.closest(queries.row(q).transpose()).triangle);
  }
  EXPECT_EQ(found[0], found[1]);
}

TEST(NearestTriangles, NoTrianglesNoHit) {
  const Mesh mesh = random_triangles(10, 1);
  const std::vector<int> none;
  const detail::NearestTriangles tree(mesh, &none, false);
  EXPECT_TRUE(tree.empty());
  EXPECT_EQ(tree.closest(Eigen::Vector3d::Zero()).triangle, -1);
}
