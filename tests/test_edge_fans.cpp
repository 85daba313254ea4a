// Edge fans (LocalReconstructionOptions::edge_fans): every triangle lies in one cell or two that
// share a face and every vertex stays in its cell, edge or face, so the mesh never crosses itself
// and leaves no sample on the wrong side, with no repair, on fields made to break it; exact on a
// plane; bricks of any size give one brick's mesh bit for bit.
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <random>
#include <string>

#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/sdf_input.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/local_brick.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

// The default path's brick options with edge fans (or the plain dual mesh without its
// untangling, fans = false), on `band` spacings; with `finer`, on the grid of twice the
// resolution that shows the thin parts (thin_parts.h).
LocalBrickOptions fan_options(bool fans, double band, bool lattice, bool finer = false) {
  ContourOptions c;
  c.local.edge_fans = fans;
  c.band.band = band;
  c.gradient_source = lattice ? GradientSource::Lattice : GradientSource::Regular;
  LocalBrickOptions o = local_brick_options(c);
  o.subdivisions = 0;
  o.thin_parts = finer ? 1 : 0;
  o.untangle = false;
  o.side_rounds = 0;
  return o;
}

Mesh bricked(const Grid& g, const LocalBrickOptions& o, int brick = 0, int threads = 2) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  return local_mesh_in_bricks(view_of(g), o, brick);
}

// Samples (not 0) whose side of `m` (its winding number) differs from their value's sign.
long samples_on_the_wrong_side(const Grid& g, const Mesh& m) {
  const MeshSdf sdf(m);
  const Samples s = g.to_samples();
  long wrong = 0;
  for (Eigen::Index i = 0; i < s.values.size(); ++i)
    if (s.values[i] != 0 && sdf.inside(s.points.row(i).transpose()) != (s.values[i] < 0)) ++wrong;
  return wrong;
}

// An n^3 grid on [-1, 1]^3 from f(i, j, k), positive on its sides (a closed surface inside).
template <class F>
Grid grid_from(int n, F f) {
  Grid g;
  g.dims = {n, n, n};
  g.values.resize(Eigen::Index(n) * n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const bool side = std::min({i, j, k}) == 0 || std::max({i, j, k}) == n - 1;
        g.values[Eigen::Index(g.index(i, j, k))] = side ? 1.0 : f(i, j, k);
      }
  return g;
}

// Fields made to break a dual mesh: random signs (every ambiguous face and cube), values a hair
// from zero (vertices squeezed into corners), thin plates between the samples at random tilts,
// and unions of random spheres (creases, near-tangent parts).
std::vector<std::pair<std::string, Grid>> adversarial_fields() {
  std::vector<std::pair<std::string, Grid>> out;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const int n = 14;
  const double h = 2.0 / (n - 1);
  for (int t = 0; t < 8; ++t)
    out.push_back({"random signs " + std::to_string(t),
                   grid_from(n, [&](int, int, int) { return u(rng) * h; })});
  for (int t = 0; t < 8; ++t)
    out.push_back({"near zero " + std::to_string(t), grid_from(n, [&](int, int, int) {
                     const double v = u(rng);
                     return (std::abs(v) < 0.3 ? 1e-9 : 1.0) * v * h;
                   })});
  for (int t = 0; t < 8; ++t) {
    const Eigen::Vector3d normal = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double thickness = (0.1 + 0.4 * (u(rng) + 1) / 2) * h, offset = u(rng) * 0.5 * h;
    out.push_back({"thin plate " + std::to_string(t), grid_from(n, [&](int i, int j, int k) {
                     const Eigen::Vector3d p(-1 + i * h, -1 + j * h, -1 + k * h);
                     const double slab = std::abs(p.dot(normal) - offset) - thickness / 2;
                     return std::max(slab, (p.cwiseAbs().maxCoeff() - 0.7));
                   })});
  }
  for (int t = 0; t < 8; ++t) {
    std::vector<std::pair<Eigen::Vector3d, double>> spheres;
    for (int s = 0; s < 6; ++s)
      spheres.push_back({0.5 * Eigen::Vector3d(u(rng), u(rng), u(rng)), 0.1 + 0.15 * (u(rng) + 1)});
    out.push_back({"spheres " + std::to_string(t), grid_from(n, [&](int i, int j, int k) {
                     const Eigen::Vector3d p(-1 + i * h, -1 + j * h, -1 + k * h);
                     double d = 1e9;
                     for (const auto& [c, r] : spheres) d = std::min(d, (p - c).norm() - r);
                     return d;
                   })});
  }
  return out;
}

}  // namespace

// The fans hold on every adversarial field, for both gradients and bands of 2 and 8 spacings;
// the same fields split along a diagonal without the untangling do cross (the test has teeth).
TEST(EdgeFans, AdversarialFieldsNeitherCrossNorLeaveASampleOnTheWrongSide) {
  long diagonal_crossings = 0;
  for (const auto& [name, g] : adversarial_fields()) {
    for (const bool lattice : {false, true})
      for (const double band : {2.0, 8.0}) {
        SCOPED_TRACE(name + (lattice ? " lattice" : " regular") + " band " + std::to_string(band));
        const Mesh m = bricked(g, fan_options(true, band, lattice));
        ASSERT_GT(m.triangles.rows(), 0);
        test::expect_closed_and_outward(m);
        EXPECT_TRUE(test::vertices_manifold(m));
        EXPECT_TRUE(self_intersecting_triangles(m).empty());
        EXPECT_EQ(samples_on_the_wrong_side(g, m), 0);
      }
    // On the finer grid (its own samples' signs, the thin parts' markers) as well.
    for (const bool lattice : {false, true}) {
      SCOPED_TRACE(name + (lattice ? " lattice" : " regular") + " on the finer grid");
      const Mesh m = bricked(g, fan_options(true, 8, lattice, true));
      ASSERT_GT(m.triangles.rows(), 0);
      test::expect_closed_and_outward(m);
      EXPECT_TRUE(test::vertices_manifold(m));
      EXPECT_TRUE(self_intersecting_triangles(m).empty());
      EXPECT_EQ(samples_on_the_wrong_side(g, m), 0);
    }
    diagonal_crossings +=
        long(self_intersecting_triangles(bricked(g, fan_options(false, 8, false))).size());
  }
  EXPECT_GT(diagonal_crossings, 0);
}

// A plane's edge crossings and cell vertices lie on it: every vertex is exact.
TEST(EdgeFans, APlaneIsExact) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const int n = 20;
  const double h = 2.0 / (n - 1);
  // The plane runs through the box: its mesh ends on the box's sides.
  Grid g;
  g.dims = {n, n, n};
  g.values.resize(Eigen::Index(n) * n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        g.values[Eigen::Index(g.index(i, j, k))] =
            Eigen::Vector3d(-1 + i * h, -1 + j * h, -1 + k * h).dot(normal) - 0.05;
  const Mesh m = bricked(g, fan_options(true, 4, true));
  ASSERT_GT(m.triangles.rows(), 100);
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
    EXPECT_NEAR(m.vertices.row(v).dot(normal) - 0.05, 0, 1e-12) << v;
  EXPECT_TRUE(self_intersecting_triangles(m).empty());
}

// The projection's and the cells' robust rounds left to the local reconstruction: none for edge
// fans on the grid itself; two (projection) and three (cells) otherwise (the default, fans on the
// finer grid); a number given is kept.
TEST(EdgeFans, RobustRoundsAreChosenOnlyWhenLeftToTheReconstruction) {
  ContourOptions c;
  EXPECT_EQ(c.local_projection.robust_rounds, kAutoRobustRounds);
  EXPECT_EQ(c.local.robust_rounds, kAutoRobustRounds);
  EXPECT_EQ(local_brick_options(c).projection.robust_rounds, 2);
  EXPECT_EQ(local_brick_options(c).local.robust_rounds, 3);
  c.local.edge_fans = true;
  EXPECT_EQ(local_brick_options(c).projection.robust_rounds, 0);
  EXPECT_EQ(local_brick_options(c).local.robust_rounds, 0);
  c.thin_parts = Switch::On;
  EXPECT_EQ(local_brick_options(c).projection.robust_rounds, 2);
  EXPECT_EQ(local_brick_options(c).local.robust_rounds, 3);
  c.thin_parts = Switch::Auto;
  c.local_projection.robust_rounds = 2;
  c.local.robust_rounds = 1;
  EXPECT_EQ(local_brick_options(c).projection.robust_rounds, 2);
  EXPECT_EQ(local_brick_options(c).local.robust_rounds, 1);
  // The fans run no carving round (their regions need no repair); the repaired mesh runs three.
  EXPECT_EQ(local_brick_options(c).carve_passes, 0);
  EXPECT_TRUE(local_brick_options(c).carve);  // (the spheres still bound the edges' vertices)
  c.local.edge_fans = false;
  EXPECT_EQ(local_brick_options(c).carve_passes, 3);
}

// A vertex whose projection lands just beyond its cell's side slides along that side back to the
// surface instead of staying a clamp's length inside it: on the torus at 32^3 (lattice gradients,
// a band of 2) the worst vertex lies 0.030 h from the surface (0.094 h clamped), at 64^3
// 0.015 h (0.066 h).
TEST(EdgeFans, VerticesHeldInTheirCellsStayOnTheSurface) {
  const auto torus = make_builtin_shape("torus");
  for (const auto& [n, worst] : {std::pair{32, 0.04}, std::pair{64, 0.02}}) {
    const Grid g = sample_grid(*torus, n, Bounds{});
    const double h = g.spacing().maxCoeff();
    const Mesh m = bricked(g, fan_options(true, 2, true));
    double farthest = 0;
    for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
      farthest = std::max(farthest, std::abs(torus->distance(m.vertices.row(v).transpose())));
    EXPECT_LT(farthest, worst * h) << n;
    EXPECT_TRUE(self_intersecting_triangles(m).empty()) << n;
    EXPECT_EQ(samples_on_the_wrong_side(g, m), 0) << n;
  }
}

// An edge's vertex lies outside both its samples' spheres (radius |value|, which hold no surface
// on an exact distance): on the torus at 32^3 and 64^3 with lattice gradients on a band of 2.
// Before the spheres bounded it, the plane through the projected vertex put about a tenth of
// them inside one (up to 0.14 h deep on the shared meshes at 64^3).
// Without robust reweighting the cells' vertices sit where their contact points' quadric puts
// them, not drawn towards the points that agree most: the fans' triangles then lie closer to a
// smooth surface (the torus at 64^3: their centroids 0.75x as far as with three rounds; the
// shared meshes at 384^3, L1 0.84x, docs/results/fan_rounds_s69.md).
TEST(EdgeFans, CellsWithoutRobustRoundsLieCloserToASmoothSurface) {
  const auto torus = make_builtin_shape("torus");
  const Grid g = sample_grid(*torus, 64, Bounds{});
  LocalBrickOptions o = fan_options(true, 2, true);
  ASSERT_EQ(o.local.robust_rounds, 0);
  const double plain = test::mean_centroid_distance(bricked(g, o), *torus);
  o.local.robust_rounds = 3;
  const double reweighed = test::mean_centroid_distance(bricked(g, o), *torus);
  std::cout << "centroids' mean distance: " << plain << " without rounds, " << reweighed
            << " with three\n";
  EXPECT_LT(plain, 0.9 * reweighed);
}

TEST(EdgeFans, EdgeVerticesStayOutOfTheirSamplesSpheres) {
  const auto torus = make_builtin_shape("torus");
  for (const int n : {32, 64}) {
    const Grid g = sample_grid(*torus, n, Bounds{});
    const double h = g.spacing().maxCoeff();
    const Mesh m = bricked(g, fan_options(true, 2, true));
    long on_edges = 0, inside = 0;
    for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
      // A vertex on a grid edge: two coordinates on the lattice's lines.
      std::array<double, 3> at;
      int free_axis = -1, on_lines = 0;
      for (int a = 0; a < 3; ++a) {
        at[std::size_t(a)] = (m.vertices(v, a) + 1) / h;
        if (std::abs(at[std::size_t(a)] - std::round(at[std::size_t(a)])) < 1e-9)
          ++on_lines;
        else
          free_axis = a;
      }
      if (on_lines != 2) continue;
      std::array<int, 3> lo;
      for (int a = 0; a < 3; ++a)
        lo[std::size_t(a)] =
            int(a == free_axis ? std::floor(at[std::size_t(a)]) : std::round(at[std::size_t(a)]));
      std::array<int, 3> hi = lo;
      ++hi[std::size_t(free_axis)];
      const double v0 = std::abs(g.values[Eigen::Index(g.index(lo[0], lo[1], lo[2]))]);
      const double v1 = std::abs(g.values[Eigen::Index(g.index(hi[0], hi[1], hi[2]))]);
      ++on_edges;
      const double from = (at[std::size_t(free_axis)] - lo[std::size_t(free_axis)]) * h;
      if (from < v0 - 1e-9 * h || h - from < v1 - 1e-9 * h) ++inside;
    }
    EXPECT_GT(on_edges, 1000) << n;
    EXPECT_EQ(inside, 0) << n;
    EXPECT_TRUE(self_intersecting_triangles(m).empty()) << n;
  }
}

// contour()'s default fans the grid's edges from kEdgeFansFrom samples along its longest axis and
// repairs below (auto_edge_fans): on a long, thin grid around a sphere (384 and 383 samples by 16
// by 16), the default's mesh is --edge-fans on's at 384 and --edge-fans off's at 383, and the
// fanned one is closed with no crossing.
TEST(EdgeFans, OnByDefaultFromKEdgeFansFromSamplesPerAxis) {
  EXPECT_FALSE(auto_edge_fans(kEdgeFansFrom - 1));
  EXPECT_TRUE(auto_edge_fans(kEdgeFansFrom));
  for (const int n : {kEdgeFansFrom - 1, kEdgeFansFrom}) {
    Grid g;
    g.dims = {n, 16, 16};
    const double h = 0.05;
    g.bounds.min = Eigen::Vector3d(-h * (n - 1) / 2, -h * 15 / 2, -h * 15 / 2);
    g.bounds.max = -g.bounds.min;
    g.values.resize(Eigen::Index(g.size()));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < 16; ++j)
        for (int k = 0; k < 16; ++k)
          g.values[Eigen::Index(g.index(i, j, k))] = g.point(i, j, k).norm() - 0.27;
    auto run = [&](Switch fans) {
      ContourOptions o;
      o.edge_fans = fans;
      return contour(grid_input(g), o);
    };
    const ContourResult automatic = run(Switch::Auto);
    const ContourResult chosen = run(n >= kEdgeFansFrom ? Switch::On : Switch::Off);
    ASSERT_TRUE(automatic.mesh && chosen.mesh) << n;
    EXPECT_EQ(automatic.edge_fans, n >= kEdgeFansFrom) << n;
    EXPECT_TRUE(automatic.mesh->vertices == chosen.mesh->vertices) << n;
    EXPECT_TRUE(automatic.mesh->triangles == chosen.mesh->triangles) << n;
    test::expect_closed_and_outward(*automatic.mesh);
    EXPECT_TRUE(self_intersecting_triangles(*automatic.mesh).empty()) << n;
  }
}

// Bricks of 8, 16 and 64 samples give the one-brick mesh bit for bit, for 1 and 2 threads, on a
// CSG shape (creases, corners), also on the finer grid, and a torus at 32^3, with the curved
// faces split (a band of 3 spacings: bricks of 8 read blocks of about 30 samples).
TEST(EdgeFans, BricksEqualOneBrickBitForBit) {
  for (const auto& [shape, finer] :
       {std::pair{"csg", false}, std::pair{"torus", false}, std::pair{"csg", true}}) {
    SCOPED_TRACE(std::string(shape) + (finer ? " on the finer grid" : ""));
    const Grid g = sample_grid(*make_builtin_shape(shape), 32, Bounds{});
    LocalBrickOptions o = fan_options(true, 3, false, finer);
    o.split_sag = 0.002;
    const Mesh whole = bricked(g, o, 0, 1);
    ASSERT_GT(whole.triangles.rows(), 1000);
    test::expect_closed_and_outward(whole);
    EXPECT_TRUE(self_intersecting_triangles(whole).empty());
    EXPECT_EQ(samples_on_the_wrong_side(g, whole), 0);
    for (const auto& [brick, threads] : {std::pair{8, 2}, std::pair{16, 1}, std::pair{64, 2}}) {
      const Mesh m = bricked(g, o, brick, threads);
      EXPECT_EQ(m.vertices, whole.vertices) << brick << " " << threads;
      EXPECT_EQ(m.triangles, whole.triangles) << brick << " " << threads;
    }
  }
}
