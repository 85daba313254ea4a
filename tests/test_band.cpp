#include <cmath>

#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/pipeline/pipeline.h"
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

// The truncation found from parts' counts (Dask's bricks) equals the whole grid's, also where the
// samples at the extreme lie in several parts, each with too few alone.
TEST(Band, TruncationFromPartsEqualsTheWholeGrids) {
  const Grid exact = torus_grid(32);
  const double h = exact.spacing()[0];
  auto parts_of = [](const Grid& g, int count) {
    std::vector<TruncationCounts> parts;
    const int plane = g.dims[1] * g.dims[2];
    for (int p = 0; p < count; ++p) {
      const int first = g.dims[0] * p / count, end = g.dims[0] * (p + 1) / count;
      Grid slab;
      slab.dims = {end - first, g.dims[1], g.dims[2]};
      slab.values =
          g.values.segment(Eigen::Index(first) * plane, Eigen::Index(end - first) * plane);
      parts.push_back(truncation_counts(view_of(slab)));
    }
    return parts;
  };
  Grid outside_only = exact, few = exact;
  for (Eigen::Index i = 0; i < outside_only.values.size(); ++i)
    outside_only.values[i] = std::min(outside_only.values[i], 2 * h);
  // 200 samples at the largest value in each of the first and last slabs: together over 1% of
  // the outside samples, as the rule asks, in two parts.
  const double top = few.values.maxCoeff() + h;
  const int plane = few.dims[1] * few.dims[2];
  for (int i = 0; i < 200; ++i) {
    few.values[i] = top;
    few.values[(few.dims[0] - 1) * plane + i] = top;
  }
  for (const Grid& g : {exact, clamped(exact, 3 * h), outside_only, few}) {
    const Truncation whole = detect_truncation(view_of(g));
    for (int count : {1, 2, 5}) {
      const Truncation t = truncation_of_parts(parts_of(g, count));
      EXPECT_EQ(t.inside, whole.inside) << count;
      EXPECT_EQ(t.outside, whole.outside) << count;
    }
  }
  EXPECT_EQ(detect_truncation(view_of(few)).outside, top);
  EXPECT_EQ(truncation_of_parts(parts_of(few, 5)).inside, std::numeric_limits<double>::infinity());
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
  // (Poisson: with no band but the truncation, the local reconstruction cannot go in bricks.)
  o.reconstruction = Reconstruction::Poisson;
  o.poisson.depth = 7;
  o.band.band = std::numeric_limits<double>::infinity();  // the truncation alone cuts
  const ContourResult a = contour(truncated, o);
  EXPECT_TRUE(a.truncation.detected());
  o.band.band = 0.999;  // + the margin of 1: 1.999
  const ContourResult b = contour(exact_input, o);
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
  EXPECT_GT(contour(truncated, o).band_samples, a.band_samples);
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
  const ContourResult band = contour_with_exact_sdf(input, *shape, o);
  o.band.band = std::numeric_limits<double>::infinity();
  const ContourResult all = contour_with_exact_sdf(input, *shape, o);
  EXPECT_LT(band.band_samples, all.band_samples / 3);
  EXPECT_LT(mean_error(band), 1e-3 * h);
  EXPECT_LT(mean_error(band), 2 * mean_error(all) + 1e-6 * h);
  // Every contact point names an input sample within the band.
  for (int s : band.contact_points->samples) EXPECT_LE(std::abs(grid.values[s]), 4 * h);
}

// The automatic band: 8 spacings below 128 samples per axis, 4 from 128, 3 from 256 (as the
// result says).
TEST(Band, AutoBandFollowsTheResolution) {
  EXPECT_EQ(auto_band(32), 8);
  EXPECT_EQ(auto_band(127), 8);
  EXPECT_EQ(auto_band(128), 4);
  EXPECT_EQ(auto_band(255), 4);
  EXPECT_EQ(auto_band(256), 3);
  EXPECT_EQ(auto_band(1024), 3);
  // The local reconstruction's: 8 below 384, then the same; with the lattice's points 6 from 128.
  EXPECT_EQ(auto_local_band(128, false), 8);
  EXPECT_EQ(auto_local_band(383, false), 8);
  EXPECT_EQ(auto_local_band(384, false), 3);
  EXPECT_EQ(auto_local_band(127, true), 8);
  EXPECT_EQ(auto_local_band(128, true), 6);
  EXPECT_EQ(auto_local_band(383, true), 6);
  EXPECT_EQ(auto_local_band(384, true), 3);
  const Grid grid = torus_grid(40);
  const BandSamples b = select_band(grid, BandOptions{});
  EXPECT_EQ(b.band, 8);
  const double h = grid.spacing().maxCoeff();
  for (Eigen::Index i = 0; i < b.samples.values.size(); ++i)
    EXPECT_LE(std::abs(b.samples.values[i]), (8 + 1) * h * (1 + 1e-12));
  ContourOptions o;
  o.want_mesh = false;
  o.want_points = true;
  EXPECT_EQ(contour(grid_input(grid), o).band_spacings, 8);
}

// The automatic Poisson depth follows the samples per axis across the band's extent: the octree's
// finest cells are about a quarter of a spacing wide below 129 samples per axis (finer only
// multiplied the triangles: bench/poisson_depth.py) and at most about half a spacing up to
// depth 11.
TEST(Band, AutoPoissonDepthFollowsTheResolution) {
  PointMatrix corners(2, 3);
  corners << -0.9, -0.9, -0.9, 0.9, 0.9, 0.9;
  const double extent = 1.8;
  EXPECT_EQ(auto_poisson_depth(corners, extent / 15), 7);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 30), 7);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 60), 8);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 100), 8);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 200), 9);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 460), 10);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 920), 11);
  EXPECT_EQ(auto_poisson_depth(corners, extent / 4000), 11);  // deeper is the user's choice
  EXPECT_EQ(auto_poisson_depth(PointMatrix(0, 3), 0.01), 8);
}
