#include <cmath>

#include "sdfcontour/band.h"
#include "sdfcontour/bricks.h"
#include "sdfcontour/builtin_shapes.h"
#include "sdfcontour/pipeline.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

Grid torus_grid(int n) {
  return sample_grid(*make_builtin_shape("torus"), n, Bounds{});
}

// The grid with every |value| clamped at t, as a TSDF or a level set stores it.
Grid clamped(Grid grid, double t) {
  for (Eigen::Index i = 0; i < grid.values.size(); ++i)
    grid.values[i] = std::clamp(grid.values[i], -t, t);
  return grid;
}

}  // namespace

TEST(Band, KeepsExactlyTheSamplesWithinTheBand) {
  const Grid grid = torus_grid(20);
  const double h = grid.spacing().maxCoeff();
  BandOptions o;
  o.band = 2.5;
  const BandSamples b = select_band(grid, o);
  // The band proper (core) and its margin of one spacing.
  long expected = 0, expected_core = 0;
  for (Eigen::Index i = 0; i < grid.values.size(); ++i) {
    expected += std::abs(grid.values[i]) <= 3.5 * h;
    expected_core += std::abs(grid.values[i]) <= 2.5 * h;
  }
  ASSERT_EQ(b.samples.values.size(), expected);
  EXPECT_EQ(std::count(b.core.begin(), b.core.end(), 1), expected_core);
  EXPECT_LT(expected, grid.values.size() / 2);
  EXPECT_FALSE(b.truncation.detected());
  for (Eigen::Index r = 0; r < b.samples.values.size(); ++r) {
    const long p = b.source[std::size_t(r)];
    EXPECT_EQ(b.samples.values[r], grid.values[p]);
    EXPECT_EQ(bool(b.core[std::size_t(r)]), std::abs(grid.values[p]) <= 2.5 * h);
    const int k = int(p % 20), j = int(p / 20 % 20), i = int(p / 400);
    EXPECT_EQ((b.samples.points.row(r).transpose() - grid.point(i, j, k)).norm(), 0.0);
  }
  o.band = std::numeric_limits<double>::infinity();
  EXPECT_EQ(select_band(grid, o).samples.values.size(), grid.values.size());
}

TEST(Band, RejectsBadBandsAndEmptyBands) {
  const Grid grid = torus_grid(12);
  BandOptions o;
  o.band = -1;
  EXPECT_THROW(select_band(grid, o), Error);
  o.band = std::nan("");
  EXPECT_THROW(select_band(grid, o), Error);
  o.band = 1e-9;  // no sample that close to the surface
  EXPECT_THROW(select_band(grid, o), Error);
  o.band = 3;
  o.truncation_mode = TruncationMode::Given;
  o.truncation = -1;
  EXPECT_THROW(select_band(grid, o), Error);
}

TEST(Band, DetectsTruncationOnlyWhereValuesAreClamped) {
  const Grid exact = torus_grid(32);
  EXPECT_FALSE(detect_truncation(exact.values).detected());
  const double h = exact.spacing()[0];
  const Truncation t = detect_truncation(clamped(exact, 3 * h).values);
  EXPECT_DOUBLE_EQ(t.inside, 3 * h);
  EXPECT_DOUBLE_EQ(t.outside, 3 * h);
  // Clamped on the outside only (the torus's inside is thinner than 6h at 32^3).
  Grid outside_only = exact;
  for (Eigen::Index i = 0; i < outside_only.values.size(); ++i)
    outside_only.values[i] = std::min(outside_only.values[i], 2 * h);
  const Truncation o = detect_truncation(outside_only.values);
  EXPECT_DOUBLE_EQ(o.outside, 2 * h);
  EXPECT_EQ(o.inside, std::numeric_limits<double>::infinity());
}

// A truncated grid gives the same contact points and mesh as the exact grid restricted to the
// band the truncation leaves: the clamped samples never reach the triangulation, and the last
// spacing inside the truncation is the band's margin.
TEST(Band, TruncatedGridEqualsTheExactGridInTheBand) {
  const Grid exact = torus_grid(32);
  const double h = exact.spacing().maxCoeff();
  const SdfInput truncated = grid_input(clamped(exact, 2 * h));
  const SdfInput exact_input = grid_input(exact);
  // No exact value lies between the cut-offs compared, so both keep the same samples.
  for (Eigen::Index i = 0; i < exact.values.size(); ++i) {
    const double v = std::abs(exact.values[i]);
    ASSERT_FALSE(v > 1.999 * h && v < 2 * h);
    ASSERT_FALSE(v > 0.999 * h && v <= 1.000001 * h);
  }
  ContourOptions o;
  o.want_points = true;
  o.poisson.depth = 7;
  o.band.band = std::numeric_limits<double>::infinity();  // the truncation alone cuts
  const ContourResult a = contour(truncated, nullptr, o);
  EXPECT_TRUE(a.truncation.detected());
  o.band.band = 0.999;  // + the margin of 1: 1.999
  const ContourResult b = contour(exact_input, nullptr, o);
  EXPECT_FALSE(b.truncation.detected());
  ASSERT_EQ(a.band_samples, b.band_samples);
  ASSERT_EQ(a.contact_points->size(), b.contact_points->size());
  EXPECT_EQ(a.contact_points->samples, b.contact_points->samples);
  EXPECT_EQ((a.contact_points->points - b.contact_points->points).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(a.mesh->vertices.rows(), b.mesh->vertices.rows());
  EXPECT_EQ((a.mesh->vertices - b.mesh->vertices).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.mesh->triangles, b.mesh->triangles);
  // Without the detection, the clamped samples would be taken for distances.
  o.band.band = std::numeric_limits<double>::infinity();
  o.band.truncation_mode = TruncationMode::None;
  EXPECT_GT(contour(truncated, nullptr, o).band_samples, a.band_samples);
}

// The band keeps the accuracy: contact points of the band's samples lie as close to the
// surface as those of every sample, and the mesh stays as close.
TEST(Band, BandContactPointsAreAsGoodAsAllSamples) {
  const auto shape = make_builtin_shape("torus");
  const Grid grid = torus_grid(40);
  const double h = grid.spacing().maxCoeff();
  ContourOptions o;
  o.want_points = true;
  o.poisson.depth = 7;
  o.band.band = 4;
  auto mean_error = [&](const ContourResult& r) {
    double sum = 0;
    for (Eigen::Index i = 0; i < r.contact_points->points.rows(); ++i)
      sum += std::abs(shape->distance(r.contact_points->points.row(i).transpose()));
    return sum / double(r.contact_points->points.rows());
  };
  const SdfInput input = grid_input(grid);
  const ContourResult band = contour(input, shape.get(), o);
  o.band.band = std::numeric_limits<double>::infinity();
  const ContourResult all = contour(input, shape.get(), o);
  EXPECT_LT(band.band_samples, all.band_samples / 3);
  EXPECT_LT(mean_error(band), 1e-3 * h);
  EXPECT_LT(mean_error(band), 2 * mean_error(all) + 1e-6 * h);
  // Every contact point names an input sample within the band.
  for (int s : band.contact_points->samples) EXPECT_LE(std::abs(grid.values[s]), 4 * h);
}

namespace {

// The global computation the bricks must reproduce.
ContactPoints global_contact_points(const BandSamples& band, const ContactPointOptions& contact) {
  const Samples& s = band.samples;
  const Triangulation tri = triangulate(s.points, s.values);
  const PointMatrix g = vertex_gradients(s.points, s.values, tri, GradientOptions{});
  return gradient_contact_points(s.points, s.values, g, tri, contact, &band.core);
}

void expect_same(const ContactPoints& a, const ContactPoints& b) {
  ASSERT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.hidden, b.hidden);
  EXPECT_EQ(a.zero_gradient, b.zero_gradient);
  EXPECT_EQ(a.discarded, b.discarded);
  EXPECT_EQ(a.rescued, b.rescued);
  // Bit for bit: the same stars, summed in the same order.
  EXPECT_EQ((a.points - b.points).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((a.normals - b.normals).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace

// Bricks give exactly the global triangulation's contact points, on a grid's band and on
// scattered samples, with small bricks and a thin first halo so that retries happen.
TEST(Bricks, EqualTheGlobalTriangulation) {
  for (const auto& [name, fn] : {std::pair<std::string, bool>{"torus", false}, {"box", true}}) {
    SCOPED_TRACE(name);
    const Grid grid = sample_grid(*make_builtin_shape(name), 32, Bounds{});
    const BandSamples band = select_band(grid, BandOptions{});
    ContactPointOptions contact;
    contact.try_tet_gradients = fn;
    const ContactPoints global = global_contact_points(band, contact);
    BrickOptions o;
    o.size = 12;
    o.halo = 5;
    BrickStats stats;
    const ContactPoints bricks =
        brick_contact_points(band.samples, band.spacing, {}, contact, o, &stats, {}, &band.core);
    std::cout << name << ": " << stats.bricks << " bricks, " << stats.retries << " retries, "
              << stats.triangulated << " samples triangulated for " << band.samples.values.size()
              << "\n";
    EXPECT_GT(stats.bricks, 8);
    EXPECT_GT(stats.retries, 0);
    expect_same(bricks, global);
  }
  // Scattered samples.
  const auto shape = make_builtin_shape("csg");
  const Samples random = sample_random(*shape, 4000, Bounds{}, 5);
  const BandSamples band = select_band(random, BandOptions{});
  BrickOptions o;
  o.size = 5;
  o.halo = 3;
  BrickStats stats;
  expect_same(brick_contact_points(band.samples, band.spacing, {}, {}, o, &stats, {}, &band.core),
              global_contact_points(band, {}));
  EXPECT_GT(stats.bricks, 8);
}

// The automatic side: the largest candidate that still gives 4 bricks per thread, and the
// automatic bricks' contact points are the global ones.
TEST(Bricks, AutomaticSizeKeepsFourBricksPerThread) {
  // A plane of points 1000 spacings wide (spacing 1): 256-spacing bricks make 4 x 4 of them.
  PointMatrix plane(200 * 200, 3);
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) plane.row(i * 200 + j) << 5.0 * i, 5.0 * j, 0.0;
  EXPECT_EQ(auto_brick_size(plane, 1.0, 1), 256);  // 16 bricks
  EXPECT_EQ(auto_brick_size(plane, 1.0, 8), 192);  // 6 x 6 = 36 >= 32
  EXPECT_EQ(auto_brick_size(plane, 1.0, 64), 64);  // no candidate makes 256 bricks
  EXPECT_THROW(auto_brick_size(plane, 0.0, 1), Error);

  const Grid grid = sample_grid(*make_builtin_shape("torus"), 32, Bounds{});
  const BandSamples band = select_band(grid, BandOptions{});
  BrickOptions o;  // size automatic
  o.halo = 2 * band.samples.values.cwiseAbs().maxCoeff() / band.spacing;
  BrickStats stats;
  expect_same(brick_contact_points(band.samples, band.spacing, {}, {}, o, &stats, {}, &band.core),
              global_contact_points(band, {}));
  EXPECT_EQ(stats.size, 64);  // a 32^3 band is one brick of any candidate size
}

TEST(Bricks, RejectBadOptions) {
  const Grid grid = sample_grid(*make_builtin_shape("sphere"), 12, Bounds{});
  const BandSamples band = select_band(grid, BandOptions{});
  BrickOptions o;
  o.size = 0;
  EXPECT_THROW(brick_contact_points(band.samples, band.spacing, {}, {}, o), Error);
  o.size = 8;
  o.halo = 0;
  EXPECT_THROW(brick_contact_points(band.samples, band.spacing, {}, {}, o), Error);
}

// The automatic band: 8 spacings below 128 samples per axis, 4 from 128 (as the result says).
TEST(Band, AutoBandFollowsTheResolution) {
  EXPECT_EQ(auto_band(32), 8);
  EXPECT_EQ(auto_band(127), 8);
  EXPECT_EQ(auto_band(128), 4);
  EXPECT_EQ(auto_band(512), 4);
  const Grid grid = torus_grid(40);
  const BandSamples b = select_band(grid, BandOptions{});
  EXPECT_EQ(b.band, 8);
  const double h = grid.spacing().maxCoeff();
  for (Eigen::Index i = 0; i < b.samples.values.size(); ++i)
    EXPECT_LE(std::abs(b.samples.values[i]), (8 + 1) * h * (1 + 1e-12));
  ContourOptions o;
  o.want_mesh = false;
  o.want_points = true;
  EXPECT_EQ(contour(grid_input(grid), nullptr, o).band_spacings, 8);
}

// The automatic Poisson depth follows the samples per axis across the band's extent: the octree's
// finest cells stay at most about half a spacing wide up to depth 10.
TEST(Band, AutoPoissonDepthFollowsTheResolution) {
  PointMatrix corners(2, 3);
  corners << -0.9, -0.9, -0.9, 0.9, 0.9, 0.9;
  const double extent = 1.8;
  EXPECT_EQ(auto_poisson_depth(corners, extent / 100), 8);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 200), 9);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 460), 10);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 2000), 10);  // deeper is the user's choice
  EXPECT_EQ(auto_poisson_depth(PointMatrix(0, 3), 0.01), 8);
}
