// Sphere carving (sphere_carving.h): a mesh moved out of the empty spheres of exact signed
// distance samples.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/metrics/metrics.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

const std::string kMeshes = SDFCONTOUR_SHARED_DIR "/data/meshes/";

// The exact sphere (radius 0.6) sampled on an n^3 grid over [-1, 1]^3, within `band` spacings.
Samples sphere_band(int n, double band) {
  const PointMatrix all = test::grid_points(n);
  const double h = 2.0 / (n - 1);
  std::vector<Eigen::Index> keep;
  Eigen::VectorXd value(all.rows());
  for (Eigen::Index i = 0; i < all.rows(); ++i) {
    value[i] = all.row(i).norm() - 0.6;
    if (std::abs(value[i]) <= band * h) keep.push_back(i);
  }
  Samples s;
  s.points.resize(Eigen::Index(keep.size()), 3);
  s.values.resize(Eigen::Index(keep.size()));
  for (std::size_t q = 0; q < keep.size(); ++q) {
    s.points.row(Eigen::Index(q)) = all.row(keep[q]);
    s.values[Eigen::Index(q)] = value[keep[q]];
  }
  return s;
}

// Marching cubes' sphere of radius 0.6 (32^3), blown up by `factor` about the centre.
Mesh inflated_sphere(double factor) {
  const auto shape = make_builtin_shape("sphere");
  Mesh m = marching_cubes(sample_grid(*shape, 32, Bounds{}));
  m.vertices *= factor;
  return m;
}

// How deep the deepest vertex lies inside a ball, over all balls (brute force).
double deepest_inside(const Mesh& mesh, const Samples& s) {
  double deepest = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    for (Eigen::Index i = 0; i < s.points.rows(); ++i)
      deepest = std::max(deepest,
                         std::abs(s.values[i]) - (mesh.vertices.row(v) - s.points.row(i)).norm());
  return deepest;
}

}  // namespace

// A sphere mesh 5% too large cuts into the outside samples' spheres; carved, no vertex lies
// inside any of them, and every vertex is at least as close to the true sphere as before.
TEST(Carving, NoVertexStaysInsideASphere) {
  const Samples s = sphere_band(24, 4);
  const double h = 2.0 / 23;
  const Mesh before = inflated_sphere(1.05);
  ASSERT_GT(deepest_inside(before, s), 0.3 * h);
  Mesh after = before;
  CarvingOptions options;
  options.passes = 20;
  const CarvingStats stats = carve_mesh(after, s.points, s.values, h, options);
  EXPECT_LE(deepest_inside(after, s), 1e-9);
  EXPECT_GT(stats.vertices_moved, before.vertices.rows() / 2);
  EXPECT_EQ(stats.held_back, 0);
  double worst_before = 0, worst_after = 0;
  for (Eigen::Index v = 0; v < after.vertices.rows(); ++v) {
    const double e0 = std::abs(before.vertices.row(v).norm() - 0.6),
                 e1 = std::abs(after.vertices.row(v).norm() - 0.6);
    EXPECT_LE(e1, e0 + 1e-12);
    worst_before = std::max(worst_before, e0);
    worst_after = std::max(worst_after, e1);
  }
  std::cout << "worst distance to the sphere " << worst_before / h << " h -> " << worst_after / h
            << " h, " << stats.vertices_moved << " vertices moved\n";
  EXPECT_LT(worst_after, 0.5 * worst_before);
  EXPECT_EQ(after.triangles, before.triangles);
}

// The same vertices whatever the thread count.
TEST(Carving, SameResultWhateverTheThreadCount) {
  const Samples s = sphere_band(24, 4);
  Mesh one = inflated_sphere(1.02), two = one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    carve_mesh(one, s.points, s.values, 2.0 / 23);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    carve_mesh(two, s.points, s.values, 2.0 / 23);
  }
  EXPECT_EQ(one.vertices, two.vertices);
}

// A push that would turn a triangle over (its vertex pushed across the opposite edge) is held
// back to keep the triangle's side; allowed to turn 180 degrees, it flips.
TEST(Carving, TrianglesKeepTheirSide) {
  Mesh m;
  m.vertices.resize(3, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.triangles.resize(1, 3);
  m.triangles << 0, 1, 2;
  PointMatrix centre(1, 3);
  centre << -1, -1, 0;
  const Eigen::VectorXd radius = Eigen::VectorXd::Constant(1, 3.0);
  auto normal_z = [](const Mesh& t) {
    const Eigen::Vector3d a = t.vertices.row(0), b = t.vertices.row(1), c = t.vertices.row(2);
    const Eigen::Vector3d n = (b - a).cross(c - a);
    return n.z() / n.norm();
  };
  Mesh held = m, flipped = m;
  const CarvingStats stats = carve_mesh(held, centre, radius, 1.0);
  EXPECT_GT(normal_z(held), 0.5);
  EXPECT_GT(stats.held_back, 0);
  CarvingOptions anything;
  anything.max_turn_degrees = 180;
  carve_mesh(flipped, centre, radius, 1.0, anything);
  EXPECT_LT(normal_z(flipped), 0);
}

namespace {

// The cube [-1, 1]^3 as 12 outward triangles.
Mesh cube_mesh() {
  Mesh m;
  m.vertices.resize(8, 3);
  for (int v = 0; v < 8; ++v)
    m.vertices.row(v) << (v & 1 ? 1 : -1), (v & 2 ? 1 : -1), (v & 4 ? 1 : -1);
  m.triangles.resize(12, 3);
  m.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2,
      4, 6, 1, 3, 5, 3, 7, 5;
  return m;
}

}  // namespace

// No vertex lies in either sample's ball, so the vertex rounds leave the cube alone; the triangle
// rounds move its top face until the sample just above it is inside and the other's ball, which
// the face cuts, is clear of the mesh: both at least |value| inside (an independent signed
// distance). A sample too far from the surface (beyond side_reach) is not looked at.
TEST(Carving, TrianglesLeaveTheBallsAndSamplesKeepTheirSide) {
  PointMatrix p(3, 3);
  p << 0.1, 0.2, 1.01,   // inside by its value, outside the cube by 0.01
      -0.3, -0.4, 0.95,  // inside, but its ball reaches 0.03 above the top face
      0.0, 0.0, 1.5;     // outside and clear
  Eigen::VectorXd value(3);
  value << -0.02, -0.08, 0.3;
  const double spacing = 0.1;
  ASSERT_GT(MeshSdf(cube_mesh()).distance(p.row(0).transpose()), 0);
  ASSERT_GT(MeshSdf(cube_mesh()).distance(p.row(1).transpose()), -0.08);

  Mesh vertices_only = cube_mesh();
  CarvingOptions no_sides;
  no_sides.side_passes = 0;
  carve_mesh(vertices_only, p, value, spacing, no_sides);
  EXPECT_EQ(vertices_only.vertices, cube_mesh().vertices);

  Mesh carved = cube_mesh();
  const CarvingStats stats = carve_mesh(carved, p, value, spacing);
  const MeshSdf after(carved);
  EXPECT_LE(after.distance(p.row(0).transpose()), -0.02 * (1 - 1e-6));
  EXPECT_LE(after.distance(p.row(1).transpose()), -0.08 * (1 - 1e-6));
  EXPECT_EQ(stats.side_violations, 2);
  EXPECT_EQ(stats.side_violations_left, 0);
  EXPECT_EQ(stats.wrong_side_left, 0);
  EXPECT_GE(stats.side_passes, 1);
  // Only the top face's corners moved, and upwards.
  for (Eigen::Index v = 0; v < 8; ++v) {
    const Eigen::Vector3d d = carved.vertices.row(v) - cube_mesh().vertices.row(v);
    if (cube_mesh().vertices(v, 2) < 0) {
      EXPECT_EQ(d.norm(), 0.0);
    }
    EXPECT_GE(d.z(), 0.0);
    EXPECT_NEAR(d.head<2>().norm(), 0.0, 1e-12);
  }
}

// The triangle rounds run by default below 128 samples per axis, whatever the input: scattered
// samples and OpenVDB level sets count the band's extent in their spacing, as grids count their
// size (a .vdb of bunny at 256^3 ran them and took 31 s instead of 14). The same lattice band of
// a sphere, given with its own spacing (~30 samples across) and with a fifth of it (~150).
TEST(Carving, TriangleRoundsFollowTheSamplesPerAxisForScatteredSamples) {
  EXPECT_TRUE(auto_carve_sides(127.9));
  EXPECT_FALSE(auto_carve_sides(128));
  const int n = 40;
  const double h = 2.0 / (n - 1);
  const Samples band = sphere_band(n, 3);
  auto side_passes = [&](double spacing) {
    ContourOptions o;
    o.band.band = 3.5 * h / spacing;  // the same samples either way
    const ContourResult r = contour(ScatteredInput{band, spacing}, o);
    EXPECT_TRUE(r.carving.has_value());
    return r.carving ? r.carving->side_passes : -1;
  };
  EXPECT_GT(side_passes(h), 0);
  EXPECT_EQ(side_passes(h / 5), 0);
}

TEST(Carving, BadInputIsAnError) {
  Mesh m = inflated_sphere(1.0);
  const Samples s = sphere_band(16, 2);
  EXPECT_THROW(carve_mesh(m, s.points, s.values.head(3), 0.1), Error);
  EXPECT_THROW(carve_mesh(m, s.points, s.values, 0.0), Error);
  Eigen::VectorXd nan = s.values;
  nan[0] = std::nan("");
  EXPECT_THROW(carve_mesh(m, s.points, nan, 0.1), Error);
  CarvingOptions bad;
  bad.passes = -1;
  EXPECT_THROW(carve_mesh(m, s.points, s.values, 0.1, bad), Error);
  bad = CarvingOptions{};
  bad.side_passes = -1;
  EXPECT_THROW(carve_mesh(m, s.points, s.values, 0.1, bad), Error);
  bad = CarvingOptions{};
  bad.side_reach = std::nan("");
  EXPECT_THROW(carve_mesh(m, s.points, s.values, 0.1, bad), Error);
}

// GCP's carved mesh is closer to the true surface than the uncarved one (bunny and koala at
// 32^3), and no more of the samples end on the wrong side.
TEST(Carving, LowersGcpErrorOnSharedMeshes) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  for (const char* name : {"bunny", "koala_lowres"}) {
    SCOPED_TRACE(name);
    const Mesh truth = normalize_mesh(read_mesh(kMeshes + name + ".obj"), 0.9);
    const Grid grid = sample_grid(MeshSdf(truth), 32, Bounds{});
    ContourOptions carved, plain;  // (the Poisson path's carving, its triangle rounds and all)
    carved.reconstruction = plain.reconstruction = Reconstruction::Poisson;
    plain.carve = Switch::Off;
    const ContourResult a = contour(grid_input(grid), carved);
    const ContourResult b = contour(grid_input(grid), plain);
    ASSERT_TRUE(a.fallback.empty()) << a.fallback;
    ASSERT_TRUE(a.carving.has_value());
    EXPECT_FALSE(b.carving.has_value());
    EXPECT_GT(a.carving->vertices_moved, 0);
    const double la = surface_distances(*a.mesh, truth, 100000).l1,
                 lb = surface_distances(*b.mesh, truth, 100000).l1;
    std::cout << name << " 32^3: L1 " << lb << " -> " << la << " carved\n";
    EXPECT_LT(la, 0.97 * lb);
  }
}
