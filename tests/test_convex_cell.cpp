// The convex cell that the lattice's power vertices are read from (contact_points/convex_cell.h):
// its vertices against an independent computation, every triple of planes solved directly.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "contact_points/convex_cell.h"

using Eigen::Vector3d;
using sdfcontour::detail::ConvexCell;

namespace {

struct Plane {
  Vector3d normal;
  double offset;
};

// Brute force: every point where three planes meet that satisfies all of them (to `tol`),
// deduplicated to `tol`.
std::vector<Vector3d> brute_vertices(const std::vector<Plane>& planes, double tol) {
  std::vector<Vector3d> out;
  const std::size_t n = planes.size();
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b)
      for (std::size_t c = b + 1; c < n; ++c) {
        Eigen::Matrix3d m;
        m << planes[a].normal.transpose(), planes[b].normal.transpose(),
            planes[c].normal.transpose();
        const Eigen::FullPivLU<Eigen::Matrix3d> lu(m);
        if (!lu.isInvertible()) continue;
        const Vector3d x = lu.solve(Vector3d(planes[a].offset, planes[b].offset, planes[c].offset));
        bool inside = true;
        for (const Plane& p : planes) inside &= p.normal.dot(x) - p.offset <= tol;
        if (!inside) continue;
        bool seen = false;
        for (const Vector3d& y : out) seen |= (x - y).norm() <= tol;
        if (!seen) out.push_back(x);
      }
  return out;
}

std::vector<Plane> box_planes(const Vector3d& lo, const Vector3d& hi) {
  std::vector<Plane> p;
  for (int d = 0; d < 3; ++d) {
    p.push_back({-Vector3d::Unit(d), -lo[d]});
    p.push_back({Vector3d::Unit(d), hi[d]});
  }
  return p;
}

}  // namespace

TEST(ConvexCell, VerticesAreThoseOfTheIntersectionOfItsHalfSpaces) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 0.9);
  const Vector3d lo(-1, -1, -1), hi(1, 1, 1);
  int nonempty = 0;
  for (int trial = 0; trial < 200; ++trial) {
    ConvexCell cell(lo, hi);
    std::vector<Plane> planes = box_planes(lo, hi);
    const int cuts = 1 + trial % 12;
    for (int k = 0; k < cuts; ++k) {
      const Vector3d n = Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
      const double offset = u(rng);
      cell.clip(n, offset, k, 1e-12);
      planes.push_back({n, offset});
    }
    ASSERT_FALSE(cell.empty());  // (the origin is inside every cut)
    ++nonempty;
    const std::vector<Vector3d> expected = brute_vertices(planes, 1e-9);
    ASSERT_EQ(cell.vertices().size(), expected.size()) << "trial " << trial;
    for (const ConvexCell::Vertex& v : cell.vertices()) {
      double nearest = INFINITY;
      for (const Vector3d& x : expected) nearest = std::min(nearest, (v.point - x).norm());
      EXPECT_LT(nearest, 1e-9) << "trial " << trial;
      // Each vertex lies on the three planes it names.
      for (int id : v.planes) {
        const Plane& p = id < 0 ? planes[std::size_t(-id - 1)] : planes[std::size_t(6 + id)];
        EXPECT_NEAR(p.normal.dot(v.point), p.offset, 1e-9) << "trial " << trial << " plane " << id;
      }
    }
  }
  EXPECT_EQ(nonempty, 200);
}

TEST(ConvexCell, APlaneBeyondEveryVertexEmptiesItAndOneBeyondNoneLeavesIt) {
  ConvexCell cell(Vector3d(0, 0, 0), Vector3d(1, 1, 1));
  cell.clip(Vector3d(1, 0, 0), 2.0, 0, 1e-12);  // misses
  EXPECT_EQ(cell.vertices().size(), 8u);
  cell.clip(Vector3d(1, 1, 1).normalized(), 0.5 / std::sqrt(3.0), 1, 1e-12);  // the corner's tet
  EXPECT_EQ(cell.vertices().size(), 4u);
  cell.clip(Vector3d(-1, 0, 0), -0.9, 2, 1e-12);  // x >= 0.9: nothing left
  EXPECT_TRUE(cell.empty());
}
