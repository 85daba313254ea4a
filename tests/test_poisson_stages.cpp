// The Poisson solver's stages, each on a problem with a known answer.
#include <gtest/gtest.h>

#include <cmath>

#include "reconstruction/poisson/conjugate_gradients.h"
#include "reconstruction/poisson/density.h"
#include "reconstruction/poisson/extraction.h"
#include "reconstruction/poisson/indicator.h"
#include "reconstruction/poisson/normal_field.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"
#include "reconstruction/poisson/system.h"
#include "sdfcontour/metrics/mesh_properties.h"

using namespace sdfcontour;
using namespace sdfcontour::poisson;
using Eigen::Vector3d;

namespace {

UnitPoint unit_point(const Vector3d& p) {
  UnitPoint u;
  u.p = p;
  u.n = Vector3d::UnitZ();
  return u;
}

// Points on a sphere (unit-cube coordinates), each splatted at `depth`.
std::vector<UnitPoint> sphere_points(int count, int depth) {
  std::vector<UnitPoint> points;
  for (int i = 0; i < count; ++i) {
    const double z = 1 - (2.0 * i + 1) / count, r = std::sqrt(1 - z * z),
                 phi = i * M_PI * (3 - std::sqrt(5.0));
    points.push_back(unit_point(Vector3d(0.5, 0.5, 0.5) +
                                0.3 * Vector3d(r * std::cos(phi), r * std::sin(phi), z)));
    points.back().depth = depth;
  }
  return points;
}

double linear(const Vector3d& p) {
  return 0.3 + 0.7 * p.x() - 0.2 * p.y() + 0.45 * p.z();
}

Vector3d node_position(const OctreeLevel& L, Key key) {
  const auto [i, j, k] = unpack(key);
  return Vector3d(double(i), double(j), double(k)) / double(L.res);
}

// Points s apart on a square grid over [0.2, 0.8)^2 of the plane z = 0.51.
std::vector<UnitPoint> plane_patch(double s) {
  std::vector<UnitPoint> points;
  for (double x = 0.2; x < 0.8; x += s)
    for (double y = 0.2; y < 0.8; y += s) points.push_back(unit_point(Vector3d(x, y, 0.51)));
  return points;
}

}  // namespace

// A discrete harmonic function with linear boundary values is that linear function (trilinear
// elements reproduce it), so conjugate gradients must find it on the interior nodes.
TEST(PoissonStages, ConjugateGradientsSolveALaplaceProblemExactly) {
  const auto points = sphere_points(50, 3);
  const MortonRuns runs(points, 3);
  Octree tree = build_octree(points, runs, 3, 3);
  const OctreeLevel& L = tree.level(3);
  ASSERT_EQ(L.nodes.size(), 9u * 9u * 9u);
  const std::vector<char> solved = solved_nodes(L, PoissonBoundary::Dirichlet);
  const CellGrid empty_grid;
  const std::vector<Eigen::Vector3d> no_field;
  const std::vector<double> no_finer(L.nodes.size(), 0.0);
  const CellRuns no_runs;
  const LevelSystem system =
      assemble_system(L, solved, splat_divergence(L, solved, empty_grid, no_field, no_finer),
                      no_runs, 0.0, points, runs);
  std::vector<double> x(L.nodes.size());
  long unknowns = 0;
  for (std::size_t v = 0; v < x.size(); ++v) {
    x[v] = solved[v] ? 0.0 : linear(node_position(L, L.nodes[v]));
    unknowns += solved[v];
  }
  EXPECT_EQ(unknowns, 7 * 7 * 7);
  const CgState state = conjugate_gradients(L, solved, system, x, {1e-12, 500});
  EXPECT_TRUE(state.converged);
  EXPECT_GT(state.iterations, 1);
  EXPECT_LE(state.relative_residual, 1e-12);
  for (std::size_t v = 0; v < x.size(); ++v)
    EXPECT_NEAR(x[v], linear(node_position(L, L.nodes[v])), 1e-9);
  // Stopped early, it says so.
  std::vector<double> y(L.nodes.size());
  for (std::size_t v = 0; v < y.size(); ++v)
    y[v] = solved[v] ? 0.0 : linear(node_position(L, L.nodes[v]));
  const CgState early = conjugate_gradients(L, solved, system, y, {1e-12, 2});
  EXPECT_FALSE(early.converged);
  EXPECT_EQ(early.iterations, 2);
  EXPECT_GT(early.relative_residual, 1e-12);
}

// The system's product holds the screening without storing rows: with the fixed nodes at zero,
// x . A x grows by  screening * sum_p w_p chi(p)^2  (chi the trilinear interpolation of x, found
// here from the points' cells and corners directly), and the product is A's: symmetric.
TEST(PoissonStages, ScreeningTermIsTheSumOverThePoints) {
  auto points = sphere_points(3000, 5);
  for (std::size_t i = 0; i < points.size(); ++i)
    points[i].weight = 0.25 + 0.75 * double(i % 4) / 3;
  const MortonRuns runs(points, 5);
  const Octree tree = build_octree(points, runs, 3, 5);
  const OctreeLevel& L = tree.level(5);
  const std::vector<char> solved = solved_nodes(L, PoissonBoundary::Neumann);
  const CellRuns cells = cell_runs(L, runs);
  const double screening = 3.5;
  auto system = [&](double s) {
    return assemble_system(L, solved, std::vector<double>(L.nodes.size(), 0.0), cells, s, points,
                           runs);
  };
  const LevelSystem plain = system(0.0), screened = system(screening);
  std::srand(7);
  auto random_on_solved = [&] {
    std::vector<double> x(L.nodes.size(), 0.0);
    for (std::size_t v = 0; v < x.size(); ++v)
      if (solved[v]) x[v] = double(std::rand()) / RAND_MAX - 0.5;
    return x;
  };
  const std::vector<double> x = random_on_solved(), y = random_on_solved();
  std::vector<double> Ax(x.size()), Ay(x.size());
  const double xAx = multiply(L, solved, screened, x, Ax);
  std::vector<double> unused(x.size());
  const double stiffness = multiply(L, solved, plain, x, unused);
  double expected = 0;
  long points_in_solved_cells = 0;
  for (const UnitPoint& p : points) {
    const std::array<long, 3> c = {long(p.p.x() * double(L.res)), long(p.p.y() * double(L.res)),
                                   long(p.p.z() * double(L.res))};
    double chi = 0;
    bool all_solved = true;
    for (int a = 0; a < 8; ++a) {
      const long i = c[0] + (a & 1), j = c[1] + (a >> 1 & 1), k = c[2] + (a >> 2 & 1);
      const int v = L.node(i, j, k);
      ASSERT_GE(v, 0);
      all_solved = all_solved && solved[std::size_t(v)];
      double w = 1;
      for (int axis = 0; axis < 3; ++axis) {
        const double t = p.p[axis] * double(L.res) - double(c[std::size_t(axis)]);
        w *= (a >> axis & 1) ? t : 1 - t;
      }
      chi += w * x[std::size_t(v)];
    }
    points_in_solved_cells += all_solved;
    expected += p.weight * chi * chi;
  }
  ASSERT_GT(points_in_solved_cells, 2000);
  EXPECT_NEAR(xAx - stiffness, screening * expected, 1e-10 * std::abs(xAx));
  EXPECT_GT(screening * expected, 0.01 * stiffness);  // the screening is not negligible here
  multiply(L, solved, screened, y, Ay);
  double yAx = 0, xAy = 0;
  for (std::size_t v = 0; v < x.size(); ++v) yAx += y[v] * Ax[v], xAy += x[v] * Ay[v];
  EXPECT_NEAR(yAx, xAy, 1e-12 * (std::abs(yAx) + std::abs(xAx)));
  // The diagonal is A's: e_v . A e_v.
  for (std::size_t v = 0; v < x.size(); v += 97) {
    if (!solved[v]) continue;
    std::vector<double> e(x.size(), 0.0), Ae(x.size());
    e[v] = 1;
    EXPECT_NEAR(multiply(L, solved, screened, e, Ae), screened.diagonal(v), 1e-12);
  }
}

// V given by coarser quadratic B-splines: its divergence against a depth's hats taken directly
// (one depth up, or two with the middle depth's splats added on the way) equals the divergence of
// its prolongation onto that depth's own B-splines (quadratic B-splines nest).
TEST(PoissonStages, DivergenceFromCoarserSplinesEqualsThatOfTheirProlongation) {
  const auto points = sphere_points(4000, 6);
  const MortonRuns runs(points, 6);
  const Octree tree = build_octree(points, runs, 3, 6);
  const OctreeLevel &C = tree.level(4), &M = tree.level(5), &F = tree.level(6);
  ASSERT_LT(F.cells.size(), std::size_t(F.res * F.res * F.res) / 2);  // adaptive
  std::srand(11);
  auto random_field = [](std::size_t n) {
    std::vector<Vector3d> W(n);
    for (auto& w : W) w = Vector3d::Random();
    return W;
  };
  const CellGrid coarse_grid = spline_grid(C), middle_grid = spline_grid(M),
                 fine_grid = spline_grid(F);
  const std::vector<Vector3d> W = random_field(coarse_grid.keys.size());
  // The middle depth's splats: every third cell of its grid.
  CellGrid splat_cells;
  for (std::size_t c = 0; c < middle_grid.keys.size(); c += 3)
    splat_cells.keys.push_back(middle_grid.keys[c]);
  splat_cells.lines = LineIndex(splat_cells.keys);
  const std::vector<Vector3d> splats = random_field(splat_cells.keys.size());
  const std::vector<char> all(F.nodes.size(), 1), all_middle(M.nodes.size(), 1);
  const std::vector<double> zeros(F.nodes.size(), 0.0), zeros_middle(M.nodes.size(), 0.0);

  // One depth up: M's hats against C's splines.
  const std::vector<Vector3d> on_middle = prolong_splines(coarse_grid, middle_grid, W);
  std::vector<double> expected(M.nodes.size(), 0.0);
  divergence(M, middle_grid, on_middle, expected, nullptr);
  // The right-hand side is minus the divergence on the solved nodes (here all of them).
  auto expect_negated = [](const std::vector<double>& direct, const std::vector<double>& expected,
                           const char* what) {
    double largest = 0;
    for (double e : expected) largest = std::max(largest, std::abs(e));
    ASSERT_GT(largest, 0) << what;
    for (std::size_t v = 0; v < expected.size(); ++v)
      ASSERT_NEAR(direct[v], -expected[v], 1e-12 * largest) << what << " node " << v;
  };
  expect_negated(splat_divergence_from_coarser(M, all_middle, coarse_grid, W, zeros_middle),
                 expected, "middle");

  // Two depths up, with the middle depth's splats.
  std::vector<Vector3d> with_splats = on_middle;
  add_on_grid(splat_cells, splats, middle_grid, with_splats);
  std::vector<double> expected_fine(F.nodes.size(), 0.0);
  divergence(F, fine_grid, prolong_splines(middle_grid, fine_grid, with_splats), expected_fine,
             nullptr);
  const MiddleDepth middle{M, splat_cells, splats};
  expect_negated(splat_divergence_from_coarser(F, all, coarse_grid, W, zeros, &middle),
                 expected_fine, "fine");
}

// On an adaptive octree, a linear function stored at every depth's nodes is read back exactly
// anywhere (hanging nodes included), and its iso-surface is the plane, watertight against the
// domain's ring of "outside".
TEST(PoissonStages, IndicatorAndExtractionReproduceALinearField) {
  const auto points = sphere_points(2000, 6);
  const MortonRuns runs(points, 6);
  const Octree tree = build_octree(points, runs, 3, 6);
  ASSERT_EQ(tree.finest, 6);
  ASSERT_LT(tree.level(6).cells.size(), std::size_t(64 * 64 * 64) / 2);  // adaptive
  std::vector<std::vector<double>> values(tree.levels.size());
  for (int d = tree.min_depth; d <= tree.finest; ++d)
    for (Key key : tree.level(d).nodes)
      values[std::size_t(d)].push_back(linear(node_position(tree.level(d), key)));
  const Indicator chi(tree, values);
  for (int i = 0; i < 200; ++i) {
    const Vector3d p = 0.5 * (Vector3d::Random() + Vector3d::Ones());
    EXPECT_NEAR(chi.at(p), linear(p), 1e-12);
  }
  for (long i = 0; i <= 64; i += 7)
    EXPECT_NEAR(chi.at_finest_node(i, 64 - i, i / 2, -1.0),
                linear(Vector3d(double(i), double(64 - i), double(i / 2)) / 64.0), 1e-12);
  // chi = 0.8 is a plane through the cube: every vertex on it, in the frame's units.
  UnitPoints frame;
  frame.centre = Vector3d(1, 2, 3);
  frame.size = 2;
  const Mesh mesh = extract_iso_surface(chi, 0.8, frame);
  ASSERT_GT(mesh.triangles.rows(), 0);
  double worst = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    const Vector3d u =
        (mesh.vertices.row(v).transpose() - frame.centre) / frame.size + Vector3d::Constant(0.5);
    if ((u.array() > 1e-9).all() && (u.array() < 1 - 1e-9).all())
      worst = std::max(worst, std::abs(linear(u) - 0.8));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_TRUE(mesh_topology(mesh).closed);
}

// Points on a regular grid of a plane, spacing s, have density 1 / s^2 away from the edges.
TEST(PoissonStages, DensityOfARegularGridIsOneOverSpacingSquared) {
  const double s = 1.0 / 128;
  const std::vector<UnitPoint> points = plane_patch(s);
  const MortonRuns runs(points, 8);
  const SamplingDensity density(points, runs, 6);
  for (const Vector3d& p : {Vector3d(0.5, 0.5, 0.51), Vector3d(0.4, 0.6, 0.51)})
    EXPECT_NEAR(density.points_per_area(p) * s * s, 1.0, 0.1) << p.transpose();
  EXPECT_LT(density.points_per_area(Vector3d(0.5, 0.5, 0.9)), 1e-9);
}

// A plane sampled 1/128 apart holds ~1.5 points per node at depth 0.5 log2(128^2 / 1.5) = 6.71:
// degree 1 splats every normal at the nearest depth, 7; degree 2 shares it between depths 6 and 7,
// the fractional part (~0.71) going to depth 7.
TEST(PoissonStages, SplatDepthIsNearestOrSharedByTheFractionalPart) {
  const std::vector<UnitPoint> points = plane_patch(1.0 / 128);
  const MortonRuns runs(points, 8);
  const SamplingDensity density(points, runs, 6);
  const std::size_t middle = points.size() / 2;  // the patch's centre, away from its edges
  const double ideal = 0.5 * std::log2(density.points_per_area(points[middle].p) / 1.5);
  ASSERT_NEAR(ideal, 6.71, 0.08);
  std::vector<UnitPoint> nearest = points, shared = points;
  assign_areas_and_depths(nearest, density, 1.5, 2, 8, false);
  assign_areas_and_depths(shared, density, 1.5, 2, 8, true);
  EXPECT_EQ(nearest[middle].depth, 7);
  EXPECT_EQ(nearest[middle].finer_share, 0);
  EXPECT_EQ(shared[middle].depth, 6);
  EXPECT_NEAR(shared[middle].finer_share, ideal - 6, 1e-12);
  // Clamped at the finest depth: no share finer than it.
  assign_areas_and_depths(shared, density, 1.5, 2, 6, true);
  EXPECT_EQ(shared[middle].depth, 6);
  EXPECT_EQ(shared[middle].finer_share, 0);
}
