// Meshes from the real world, sampled as signed distances: overlapping parts united, zero-area
// triangles harmless, nested shells and overlaps signed by the winding number, scattered points
// grouped into the objects of a scene.
#include <cmath>

#include "sdfcontour/band/point_clusters.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_union.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

// An axis-aligned cube [lo, hi]^3, outward; `flip` turns it inside out (a cavity's wall).
Mesh cube(double lo, double hi, bool flip = false) {
  Mesh m;
  m.vertices.resize(8, 3);
  for (int v = 0; v < 8; ++v)
    m.vertices.row(v) << (v & 4 ? hi : lo), (v & 2 ? hi : lo), (v & 1 ? hi : lo);
  m.triangles.resize(12, 3);
  m.triangles << 0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0,
      6, 4, 1, 5, 7, 1, 7, 3;
  if (flip) m.triangles.col(1).swap(m.triangles.col(2));
  return m;
}

Mesh both(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  append_mesh(m, b);
  return m;
}

}  // namespace

// The union of two overlapping cubes is one closed surface without crossings, whose distance is
// the union's: the origin, inside both, lies sqrt(0.08) from its boundary (a concave corner).
TEST(MeshUnion, OverlappingPartsBecomeOneSurface) {
  const Mesh overlap = both(cube(-0.6, 0.2), cube(-0.2, 0.6));
  ASSERT_FALSE(self_intersecting_triangles(overlap).empty());
  MeshUnionStats stats;
  const Mesh united = union_of_overlapping_parts(overlap, &stats);
  EXPECT_EQ(stats.parts, 2);
  EXPECT_EQ(stats.parts_united, 1);
  EXPECT_EQ(stats.crossings_left, 0);
  EXPECT_TRUE(mesh_topology(united).closed);
  EXPECT_EQ(connected_components(united), 1);
  const MeshSdf sdf(united);
  EXPECT_NEAR(sdf.distance(Eigen::Vector3d::Zero()), -std::sqrt(0.08), 1e-12);
  EXPECT_NEAR(sdf.distance(Eigen::Vector3d(0.7, 0.4, 0.4)), 0.1, 1e-12);
  // Parts apart are left as they are.
  const Mesh apart = both(cube(-0.6, -0.3), cube(0.3, 0.6));
  const Mesh same = union_of_overlapping_parts(apart, &stats);
  EXPECT_EQ(stats.parts_united, 0);
  EXPECT_EQ(same.triangles, apart.triangles);
}

// An inside-out part crossing an outward one (the fuzzer's case: CGAL's corefinement, which
// needs solids bounded outward, looped forever on it) is kept as it is, its crossings counted;
// turned outward, the same two parts are united.
TEST(MeshUnion, InsideOutPartsAreNotUnited) {
  Mesh m;
  m.vertices.resize(8, 3);
  m.vertices << 0, 0, 0, 0.8, -0.8, -0.4, 0, -0.2, 0, 0, 0, 0.8, -0.4, -0.4, -0.4, 0.4, -0.4, 0.4,
      -0.4, 0.4, -0.4, -0.4, -0.4, 0.4;
  m.triangles.resize(8, 3);
  m.triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4, 6, 5, 4, 5, 7, 4, 7, 6, 5, 6, 7;
  ASSERT_TRUE(mesh_topology(m).closed);
  MeshUnionStats stats;
  const Mesh kept = union_of_overlapping_parts(m, &stats);
  EXPECT_EQ(stats.parts, 2);
  EXPECT_EQ(stats.parts_united, 0);
  EXPECT_GT(stats.crossings_left, 0);
  EXPECT_EQ(kept.triangles, m.triangles);
  Mesh outward = m;
  outward.triangles.topRows(4).col(1).swap(outward.triangles.topRows(4).col(2));
  const Mesh united = union_of_overlapping_parts(outward, &stats);
  EXPECT_EQ(stats.parts_united, 1);
  EXPECT_EQ(stats.crossings_left, 0);
  EXPECT_TRUE(mesh_topology(united).closed);
}

// The sign is the winding number's: inside two overlapping parts (winding 2) is inside, a cavity
// (an inward shell inside an outward one, winding 0) is outside, and parity would get the
// overlap wrong.
TEST(MeshUnion, WindingNumberSigns) {
  const MeshSdf overlap(both(cube(-0.6, 0.2), cube(-0.2, 0.6)));
  EXPECT_TRUE(overlap.inside(Eigen::Vector3d(0.01, 0.02, 0.03)));
  EXPECT_TRUE(overlap.inside(Eigen::Vector3d(-0.5, -0.5, -0.5)));
  EXPECT_FALSE(overlap.inside(Eigen::Vector3d(0.5, -0.5, 0.1)));
  const MeshSdf hollow(both(cube(-0.6, 0.6), cube(-0.3, 0.3, true)));
  EXPECT_FALSE(hollow.inside(Eigen::Vector3d(0.01, 0.02, 0.03)));
  EXPECT_TRUE(hollow.inside(Eigen::Vector3d(0.45, 0.01, 0.02)));
  EXPECT_NEAR(hollow.distance(Eigen::Vector3d(0.01, 0.02, 0.03)), 0.27, 1e-12);
  // Rays along the axes graze a cube's edges: other directions decide.
  EXPECT_TRUE(overlap.inside(Eigen::Vector3d(-0.4, -0.4, -0.4)));
}

// A zero-area triangle on a face's diagonal (a closed mesh as CAD exports leave them) samples
// as the plain cube does.
TEST(MeshUnion, ZeroAreaTrianglesAreHarmless) {
  const Mesh plain = cube(-0.5, 0.5);
  Mesh with = plain;
  with.vertices.conservativeResize(9, 3);
  with.vertices.row(8) = (plain.vertices.row(0) + plain.vertices.row(3)) / 2;
  with.triangles.resize(14, 3);
  with.triangles.topRows(10) = plain.triangles.bottomRows(10);
  with.triangles.bottomRows(4) << 0, 1, 8, 8, 1, 3, 0, 8, 3, 0, 3, 2;
  ASSERT_TRUE(mesh_topology(with).closed);
  const MeshSdf a(plain), b(with);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(-0.5, 0, 0), Eigen::Vector3d(-0.6, 0.1, 0.1),
                                   Eigen::Vector3d(-0.4, 0, 0.01), Eigen::Vector3d(0.2, 0.3, 0.1)})
    EXPECT_EQ(a.distance(p), b.distance(p));
}

// Points cluster by touching cubes; a gap of more than two cubes separates; numbering follows
// the first row; memory follows the points even a billion cubes apart.
TEST(PointClusters, SplitWhatLiesApart) {
  PointMatrix p(6, 3);
  p << 0, 0, 0, 1e9, 0, 0, 0.5, 0.5, 0, 1.4, 0.9, 0.2, 1e9 + 0.5, 0, 0, 5, 5, 5;
  EXPECT_EQ(point_clusters(p, 1.0), (std::vector<int>{0, 1, 0, 0, 1, 2}));
  EXPECT_THROW(point_clusters(p, 0.0), Error);
  EXPECT_TRUE(point_clusters(PointMatrix(0, 3), 1.0).empty());
}
