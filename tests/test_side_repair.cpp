// Side repair (side_repair.h): a mesh that bulges over an outside sample is dented locally until
// the sample is outside, without crossings, without moving anything far from the bulge, and without
// putting another sample on the wrong side.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/reconstruction/side_repair.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

constexpr double kRadius = 0.5;
constexpr int kSamples = 31;  // h = 1/15; sample (23, 15, 15) lies at x = 8/15, 0.5 h outside
const double kSpacing = 2.0 / (kSamples - 1);

// A latitude-longitude sphere of radius kRadius (edges ~0.4 h) with a bump of `height` around its
// point (kRadius, 0, 0): the bump covers the outside sample at (8/15, 0, 0).
Mesh bumped_sphere(double height) {
  const int rings = 64, segments = 128;
  const Eigen::Vector3d top(kRadius, 0, 0);
  std::vector<Eigen::Vector3d> directions{{0, 0, 1}, {0, 0, -1}};
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
      directions.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
    }
  auto ring = [&](int i, int j) { return 2 + (i - 1) * segments + (j % segments); };
  std::vector<Eigen::Vector3i> triangles;
  for (int j = 0; j < segments; ++j) {
    triangles.emplace_back(0, ring(1, j), ring(1, j + 1));
    triangles.emplace_back(1, ring(rings - 1, j + 1), ring(rings - 1, j));
    for (int i = 1; i + 1 < rings; ++i) {
      triangles.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      triangles.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  Mesh mesh;
  mesh.vertices.resize(Eigen::Index(directions.size()), 3);
  for (std::size_t v = 0; v < directions.size(); ++v) {
    const Eigen::Vector3d d = directions[v];
    const double bump =
        height * std::exp(-(kRadius * d - top).squaredNorm() / (kSpacing * kSpacing));
    mesh.vertices.row(Eigen::Index(v)) = ((kRadius + bump) * d).transpose();
  }
  mesh.triangles.resize(Eigen::Index(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    mesh.triangles.row(Eigen::Index(t)) = triangles[t].transpose();
  return mesh;
}

// The grid samples of the exact sphere within 3 spacings of its surface.
void sphere_samples(PointMatrix& points, Eigen::VectorXd& values) {
  std::vector<Eigen::Vector3d> p;
  std::vector<double> v;
  for (int i = 0; i < kSamples; ++i)
    for (int j = 0; j < kSamples; ++j)
      for (int k = 0; k < kSamples; ++k) {
        const Eigen::Vector3d x = Eigen::Vector3d(i, j, k) * kSpacing - Eigen::Vector3d::Ones();
        const double d = x.norm() - kRadius;
        if (std::abs(d) <= 3 * kSpacing) p.push_back(x), v.push_back(d);
      }
  points.resize(Eigen::Index(p.size()), 3);
  values.resize(Eigen::Index(v.size()));
  for (std::size_t q = 0; q < p.size(); ++q) {
    points.row(Eigen::Index(q)) = p[q].transpose();
    values[Eigen::Index(q)] = v[q];
  }
}

long wrong_sides(const Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values) {
  const MeshSdf own(mesh);
  long wrong = 0;
  for (Eigen::Index s = 0; s < values.size(); ++s)
    wrong += (own.distance(points.row(s).transpose()) < 0) != (values[s] < 0);
  return wrong;
}

}  // namespace

TEST(SideRepair, DentsABulgeOffAnOutsideSample) {
  Mesh mesh = bumped_sphere(0.9 * kSpacing);
  PointMatrix points;
  Eigen::VectorXd values;
  sphere_samples(points, values);
  ASSERT_GE(wrong_sides(mesh, points, values), 1);  // the bump holds the sample at (8/15, 0, 0)
  ASSERT_TRUE(self_intersecting_triangles(mesh).empty());
  const PointMatrix start = mesh.vertices;
  const SideRepairStats stats = repair_sample_sides(mesh, points, values, kSpacing);
  EXPECT_GE(stats.wrong_side, 1);
  EXPECT_EQ(stats.left, 0);
  EXPECT_EQ(stats.repaired, stats.wrong_side);
  EXPECT_EQ(wrong_sides(mesh, points, values), 0);
  EXPECT_TRUE(self_intersecting_triangles(mesh).empty());
  const MeshTopology topology = mesh_topology(mesh);
  EXPECT_TRUE(topology.closed);
  EXPECT_TRUE(topology.consistently_oriented);
  EXPECT_EQ(topology.nonmanifold_edges, 0);
  // Only the bump moved, towards the sphere (inwards along x, by less than the bump).
  long moved = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    const Eigen::Vector3d d = (mesh.vertices.row(v) - start.row(v)).transpose();
    if (d.norm() == 0) continue;
    ++moved;
    EXPECT_LT((start.row(v) - Eigen::RowVector3d(kRadius, 0, 0)).norm(), 3 * kSpacing);
    EXPECT_LT(d.norm(), kSpacing);
  }
  EXPECT_EQ(moved, stats.vertices_moved);
  EXPECT_GT(moved, 0);
}

TEST(SideRepair, LeavesAMeshWithEverySampleOnItsSideAlone) {
  Mesh mesh = bumped_sphere(0);
  PointMatrix points;
  Eigen::VectorXd values;
  sphere_samples(points, values);
  ASSERT_EQ(wrong_sides(mesh, points, values), 0);
  const PointMatrix start = mesh.vertices;
  const SideRepairStats stats = repair_sample_sides(mesh, points, values, kSpacing);
  EXPECT_EQ(stats.wrong_side, 0);
  EXPECT_EQ(stats.vertices_moved, 0);
  EXPECT_EQ(mesh.vertices, start);
}

TEST(SideRepair, RejectsBadInput) {
  Mesh mesh = bumped_sphere(0);
  PointMatrix points(2, 3);
  points.setZero();
  Eigen::VectorXd values(1);
  values << 0.1;
  EXPECT_THROW(repair_sample_sides(mesh, points, values, kSpacing), Error);
  values.resize(2);
  values << 0.1, NAN;
  EXPECT_THROW(repair_sample_sides(mesh, points, values, kSpacing), Error);
  values << 0.1, 0.2;
  EXPECT_THROW(repair_sample_sides(mesh, points, values, 0.0), Error);
  SideRepairOptions bad;
  bad.radius = 0;
  EXPECT_THROW(repair_sample_sides(mesh, points, values, kSpacing, bad), Error);
}
