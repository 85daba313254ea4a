// Degree-2 (quadratic B-spline) elements of the Poisson solver, each stage against an independent
// computation: brute-force quadrature, exact reproduction of a harmonic quadratic, and the
// refinement relation.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>

#include "reconstruction/poisson/bspline.h"
#include "reconstruction/poisson/conjugate_gradients.h"
#include "reconstruction/poisson/extraction.h"
#include "reconstruction/poisson/indicator.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"
#include "reconstruction/poisson/quadratic_basis.h"
#include "reconstruction/poisson/quadratic_system.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/reconstruction/poisson.h"

using namespace sdfcontour;
using namespace sdfcontour::poisson;
using Eigen::Vector3d;

namespace {

// Points on a sphere of radius 0.3 about the unit cube's centre, splatted at `depth`.
std::vector<UnitPoint> sphere_points(int count, int depth) {
  std::vector<UnitPoint> points;
  for (int i = 0; i < count; ++i) {
    const double z = 1 - (2.0 * i + 1) / count, r = std::sqrt(1 - z * z),
                 phi = i * M_PI * (3 - std::sqrt(5.0));
    UnitPoint u;
    u.n = Vector3d(r * std::cos(phi), r * std::sin(phi), z);
    u.p = Vector3d(0.5, 0.5, 0.5) + 0.3 * u.n;
    u.depth = depth;
    u.weight = 0.25 + 0.75 * double(i % 4) / 3;
    points.push_back(u);
  }
  return points;
}

// Sum over the coefficients of x[c] B_c(p), B_c read from the 1D B-spline directly (x with the
// ties applied).
double brute_force_value(const OctreeLevel& L, const QuadraticCells& C,
                         const std::vector<double>& x, const Vector3d& p) {
  double sum = 0;
  for (std::size_t c = 0; c < C.size(); ++c) {
    const auto o = unpack(C.grid.keys[c]);
    double b = 1;
    for (int a = 0; a < 3; ++a)
      b *= quadratic_bspline(p[a] * double(L.res) - (double(o[std::size_t(a)]) - 1) - 0.5);
    sum += b * x[c];
  }
  return sum;
}

std::vector<double> random_values(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(n);
  for (double& v : x) v = u(rng);
  return x;
}

}  // namespace

// The 1D tables against a midpoint rule on a fine subdivision, and the interior identities:
// B-splines sum to one (mass rows sum to 1), and slopes and stiffness rows sum to 0.
TEST(PoissonQuadratic, IntegralTablesMatchQuadrature) {
  const long res = 8;
  const QuadraticIntegrals I(res);
  const int steps = 20000;
  for (long i = -1; i <= res; ++i)
    for (int o = -2; o <= 2; ++o) {
      const long j = i + o;
      double m = 0, s = 0, k = 0;
      if (j >= -1 && j <= res)
        for (int q = 0; q < steps; ++q) {
          const double u = (q + 0.5) * double(res) / steps, du = double(res) / steps;
          const double ti = u - double(i) - 0.5, tj = u - double(j) - 0.5;
          m += quadratic_bspline(ti) * quadratic_bspline(tj) * du;
          s += quadratic_bspline_slope(ti) * quadratic_bspline(tj) * du;
          k += quadratic_bspline_slope(ti) * quadratic_bspline_slope(tj) * du;
        }
      const std::size_t a = std::size_t(i + 1), b = std::size_t(o + 2);
      EXPECT_NEAR(I.mass[a][b], m, 1e-7) << i << " " << o;
      EXPECT_NEAR(I.slope[a][b], s, 1e-6) << i << " " << o;
      EXPECT_NEAR(I.stiffness[a][b], k, 1e-6) << i << " " << o;
    }
  for (long i = 2; i <= res - 3; ++i) {
    double m = 0, s = 0, k = 0;
    for (int o = 0; o < 5; ++o) {
      m += I.mass[std::size_t(i + 1)][std::size_t(o)];
      s += I.slope[std::size_t(i + 1)][std::size_t(o)];
      k += I.stiffness[std::size_t(i + 1)][std::size_t(o)];
    }
    EXPECT_NEAR(m, 1, 1e-12);
    EXPECT_NEAR(s, 0, 1e-12);
    EXPECT_NEAR(k, 0, 1e-12);
  }
}

// Quadratic B-splines reproduce quadratics: u^2 = sum_i i (i + 1) B_i(u) and u = sum (i + 1/2) B_i.
// f = u^2 - v^2 + a linear term is harmonic, so with the coefficients whose supports reach the
// domain's faces fixed to f's, the Galerkin solution of Laplace's equation is f itself.
TEST(PoissonQuadratic, LaplaceSolveReproducesAHarmonicQuadratic) {
  const int depth = 3;
  const auto points = sphere_points(50, depth);
  const MortonRuns runs(points, depth);
  const Octree tree = build_octree(points, runs, depth, depth);
  const OctreeLevel& L = tree.level(depth);
  QuadraticCells C = quadratic_cells(L, PoissonBoundary::Free);
  ASSERT_EQ(C.size(), std::size_t((L.res + 2) * (L.res + 2) * (L.res + 2)));
  auto f = [](long i, long j, long k) {
    return double(i * (i + 1) - j * (j + 1)) + 0.3 + 0.7 * (i + 0.5) - 0.2 * (j + 0.5) +
           0.45 * (k + 0.5);
  };
  std::vector<double> x(C.size()), expected(C.size());
  long unknowns = 0;
  for (std::size_t c = 0; c < C.size(); ++c) {
    const auto o = unpack(C.grid.keys[c]);
    const long i = o[0] - 1, j = o[1] - 1, k = o[2] - 1;
    expected[c] = f(i, j, k);
    // B_c vanishes on the faces when its support [c - 1, c + 2] lies inside [0, res].
    C.solved[c] = i >= 1 && j >= 1 && k >= 1 && i <= L.res - 2 && j <= L.res - 2 && k <= L.res - 2;
    x[c] = C.solved[c] ? 0.0 : expected[c];
    unknowns += C.solved[c];
  }
  EXPECT_EQ(unknowns, (L.res - 2) * (L.res - 2) * (L.res - 2));
  const QuadraticIntegrals I(L.res);
  const QuadraticSystem S = assemble_quadratic_system(L, C, I, std::vector<double>(C.size(), 0.0),
                                                      CellRuns{}, 0.0, points, runs);
  const CgState state = conjugate_gradients(
      C.size(), C.solved, S.b,
      [&](const std::vector<double>& in, std::vector<double>& out) { return multiply(S, in, out); },
      [&](std::size_t c) { return S.diagonal[c]; }, x, {1e-13, 500});
  EXPECT_TRUE(state.converged);
  EXPECT_GT(state.iterations, 1);
  for (std::size_t c = 0; c < C.size(); ++c) EXPECT_NEAR(x[c], expected[c], 1e-8);
}

// The product holds the screening: x . A x grows by  screening * sum_p w_p chi(p)^2  (chi summed
// from every B-spline directly), and A is symmetric, for each boundary's ties.
TEST(PoissonQuadratic, ScreenedProductIsSymmetricAndSumsOverThePoints) {
  const int depth = 4;
  const auto points = sphere_points(800, depth);
  const MortonRuns runs(points, depth);
  const Octree tree = build_octree(points, runs, 3, depth);
  const OctreeLevel& L = tree.level(depth);
  const CellRuns cells = cell_runs(L, runs);
  const QuadraticIntegrals I(L.res);
  for (const auto boundary :
       {PoissonBoundary::Neumann, PoissonBoundary::Dirichlet, PoissonBoundary::Free}) {
    SCOPED_TRACE(poisson_boundary_name(boundary));
    const QuadraticCells C = quadratic_cells(L, boundary);
    auto on_solved = [&](unsigned seed) {
      std::vector<double> x = random_values(C.size(), seed);
      for (std::size_t c = 0; c < C.size(); ++c)
        if (!C.solved[c]) x[c] = 0;
      apply_ties(C, x);
      return x;
    };
    const std::vector<double> x = on_solved(1), y = on_solved(2);
    const double screening = 2.5;
    auto system = [&](double s) {
      return assemble_quadratic_system(L, C, I, std::vector<double>(C.size(), 0.0), cells, s,
                                       points, runs);
    };
    const QuadraticSystem plain = system(0), screened = system(screening);
    std::vector<double> Ax(C.size()), Ay(C.size()), unused(C.size());
    const double xAx = multiply(screened, x, Ax), xPx = multiply(plain, x, unused);
    multiply(screened, y, Ay);
    double xAy = 0, yAx = 0;
    for (std::size_t c = 0; c < C.size(); ++c) {
      xAy += x[c] * Ay[c];
      yAx += y[c] * Ax[c];
      if (!C.solved[c]) {
        EXPECT_EQ(Ax[c], 0.0);
      }
    }
    EXPECT_NEAR(xAy, yAx, 1e-9 * std::abs(xAy));
    double sum = 0;
    for (const UnitPoint& p : points) {
      const double chi = brute_force_value(L, C, x, p.p);
      sum += p.weight * chi * chi;
    }
    EXPECT_NEAR(xAx - xPx, screening * sum, 1e-9 * xAx);
    EXPECT_GT(xPx, 0);
  }
}

// Prolonged coefficients describe the same function on the finer depth's active cells; node
// values and point evaluation agree with the B-splines summed directly; the restriction of
// integrals is the prolongation's transpose.
TEST(PoissonQuadratic, ProlongationIsExactAndRestrictionItsTranspose) {
  const auto points = sphere_points(400, 5);
  const MortonRuns runs(points, 5);
  const Octree tree = build_octree(points, runs, 3, 5);
  for (const auto boundary : {PoissonBoundary::Neumann, PoissonBoundary::Free}) {
    SCOPED_TRACE(poisson_boundary_name(boundary));
    const OctreeLevel &coarse = tree.level(4), &fine = tree.level(5);
    const QuadraticCells Cc = quadratic_cells(coarse, boundary),
                         Cf = quadratic_cells(fine, boundary);
    std::vector<double> x = random_values(Cc.size(), 3);
    apply_ties(Cc, x);
    const std::vector<double> xf = prolong_coefficients(Cc, Cf, x);
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::size_t> pick(0, fine.cells.size() - 1);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int t = 0; t < 200; ++t) {
      const auto cell = unpack(fine.cells[pick(rng)]);
      const Vector3d p = (Vector3d(double(cell[0]), double(cell[1]), double(cell[2])) +
                          Vector3d(unit(rng), unit(rng), unit(rng))) /
                         double(fine.res);
      const double want = brute_force_value(coarse, Cc, x, p);
      EXPECT_NEAR(evaluate(fine, Cf, xf, cell, p), want, 1e-12);
      EXPECT_NEAR(evaluate(coarse, Cc, x, cell_of(p, coarse.res), p), want, 1e-12);
    }
    const std::vector<double> nodes = node_values(fine, Cf, xf);
    for (std::size_t v = 0; v < fine.nodes.size(); v += 97) {
      const auto n = unpack(fine.nodes[v]);
      const Vector3d p = Vector3d(double(n[0]), double(n[1]), double(n[2])) / double(fine.res);
      EXPECT_NEAR(nodes[v], brute_force_value(fine, Cf, xf, p), 1e-12);
    }
    // <R v, u> = <v, P u> over untied coefficients (ties are applied after a prolongation).
    if (boundary == PoissonBoundary::Free) {
      const std::vector<double> v = random_values(Cf.size(), 4);
      std::vector<double> Rv(Cc.size(), 0.0);
      restrict_integrals(Cc, Cf, v, Rv);
      double left = 0, right = 0;
      for (std::size_t c = 0; c < Cc.size(); ++c) left += Rv[c] * x[c];
      for (std::size_t f = 0; f < Cf.size(); ++f) right += v[f] * xf[f];
      EXPECT_NEAR(left, right, 1e-9 * std::abs(right));
    }
  }
}

// The divergence integrals against a field given by B-spline coefficients, by 3D Gauss quadrature
// over each coefficient's support cells.
TEST(PoissonQuadratic, DivergenceMatchesQuadrature) {
  const auto points = sphere_points(200, 3);
  const MortonRuns runs(points, 3);
  const Octree tree = build_octree(points, runs, 3, 3);
  const OctreeLevel& L = tree.level(3);
  const QuadraticCells C = quadratic_cells(L, PoissonBoundary::Free);
  const QuadraticIntegrals I(L.res);
  const CellGrid& grid = C.grid;  // the field on the same cells
  std::vector<Eigen::Vector3d> W(grid.keys.size());
  const std::vector<double> r = random_values(3 * W.size(), 9);
  for (std::size_t s = 0; s < W.size(); ++s) W[s] = Vector3d(r[3 * s], r[3 * s + 1], r[3 * s + 2]);
  std::vector<double> out(C.size(), 0.0);
  quadratic_divergence(L, C, I, grid, W, out);
  const double g = 0.5 * std::sqrt(0.6), node[3] = {0.5 - g, 0.5, 0.5 + g},
               weight[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
  for (std::size_t c = 0; c < C.size(); c += 37) {
    const auto o = unpack(C.grid.keys[c]);
    const long ci[3] = {o[0] - 1, o[1] - 1, o[2] - 1};
    double sum = 0;
    for (long a = ci[0] - 1; a <= ci[0] + 1; ++a)
      for (long b = ci[1] - 1; b <= ci[1] + 1; ++b)
        for (long e = ci[2] - 1; e <= ci[2] + 1; ++e) {
          if (a < 0 || b < 0 || e < 0 || a >= L.res || b >= L.res || e >= L.res) continue;
          for (int q = 0; q < 27; ++q) {
            const Vector3d u(double(a) + node[q % 3], double(b) + node[q / 3 % 3],
                             double(e) + node[q / 9]);
            Vector3d V = Vector3d::Zero();
            for (std::size_t s = 0; s < W.size(); ++s) {
              const auto so = unpack(grid.keys[s]);
              double bs = 1;
              for (int k = 0; k < 3; ++k)
                bs *= quadratic_bspline(u[k] - (double(so[std::size_t(k)]) - 1) - 0.5);
              V += bs * W[s];
            }
            Vector3d grad;
            for (int k = 0; k < 3; ++k) {
              grad[k] = double(L.res) * quadratic_bspline_slope(u[k] - double(ci[k]) - 0.5);
              for (int m = 0; m < 3; ++m)
                if (m != k) grad[k] *= quadratic_bspline(u[m] - double(ci[m]) - 0.5);
            }
            sum +=
                weight[q % 3] * weight[q / 3 % 3] * weight[q / 9] * grad.dot(V) * L.h * L.h * L.h;
          }
        }
    EXPECT_NEAR(out[c], sum, 1e-10);
  }
}

// End to end: a sphere from exact points comes back within 1% of a cell on average, watertight;
// free and Neumann boundaries now give different functions; the mesh does not depend on the
// thread count.
TEST(PoissonQuadratic, ReconstructsASphere) {
  const auto shape = make_builtin_shape("sphere");
  OrientedPoints input;
  const int count = 20000;
  input.points.resize(count, 3);
  input.normals.resize(count, 3);
  for (int i = 0; i < count; ++i) {
    const double z = 1 - (2.0 * i + 1) / count, r = std::sqrt(1 - z * z),
                 phi = i * M_PI * (3 - std::sqrt(5.0));
    const Vector3d n(r * std::cos(phi), r * std::sin(phi), z);
    input.normals.row(i) = n.transpose();
    input.points.row(i) = 0.6 * n.transpose();
  }
  PoissonOptions o;
  o.depth = 7;
  o.degree = 2;
  const PoissonResult neumann = poisson_reconstruct(input, o);
  const MeshTopology t = mesh_topology(neumann.mesh);
  EXPECT_TRUE(t.closed);
  EXPECT_EQ(t.euler_characteristic, 2);
  const double h = 1.2 * 1.1 / 128;
  double sum = 0;
  for (Eigen::Index v = 0; v < neumann.mesh.vertices.rows(); ++v)
    sum += std::abs(shape->distance(neumann.mesh.vertices.row(v).transpose()));
  EXPECT_LT(sum / double(neumann.mesh.vertices.rows()), 0.01 * h);
  EXPECT_NEAR(neumann.iso_value, 0.5, 0.05);
  o.boundary = PoissonBoundary::Free;
  const PoissonResult free = poisson_reconstruct(input, o);
  EXPECT_NE(free.iso_value, neumann.iso_value);
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    o.boundary = PoissonBoundary::Neumann;
    const PoissonResult serial = poisson_reconstruct(input, o);
    EXPECT_EQ(serial.iso_value, neumann.iso_value);
    EXPECT_TRUE(serial.mesh.vertices == neumann.mesh.vertices);
  }
  o.degree = 3;
  EXPECT_THROW(poisson_reconstruct(input, o), Error);
}

// chi quadratic along every edge (a sphere's squared distance): with chi at the edges' midpoints
// the extracted vertices lie on the sphere to round-off; interpolated linearly they miss it by a
// fraction of a cell.
TEST(PoissonQuadratic, EdgeRootsOfAQuadraticFieldAreExact) {
  const auto points = sphere_points(2000, 6);
  const MortonRuns runs(points, 6);
  const Octree tree = build_octree(points, runs, 3, 6);
  const Vector3d centre(0.5, 0.5, 0.5);
  auto field = [&](const Vector3d& p) { return 0.5 - 4 * ((p - centre).squaredNorm() - 0.09); };
  std::vector<std::vector<double>> values(tree.levels.size());
  for (int d = tree.min_depth; d <= tree.finest; ++d)
    for (Key key : tree.level(d).nodes) {
      const auto n = unpack(key);
      values[std::size_t(d)].push_back(
          field(Vector3d(double(n[0]), double(n[1]), double(n[2])) / double(tree.level(d).res)));
    }
  const Indicator chi(tree, values);
  const UnitPoints frame;  // unit cube in, unit cube out
  auto worst_miss = [&](const Mesh& mesh) {
    double worst = 0;
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
      worst = std::max(
          worst, std::abs((frame.to_unit(mesh.vertices.row(v).transpose()) - centre).norm() - 0.3));
    return worst;
  };
  const Mesh exact = extract_iso_surface(chi, 0.5, frame, nullptr, field);
  const Mesh linear = extract_iso_surface(chi, 0.5, frame, nullptr);
  EXPECT_EQ(exact.vertices.rows(), linear.vertices.rows());
  EXPECT_TRUE(mesh_topology(exact).closed);
  EXPECT_LT(worst_miss(exact), 1e-12);
  EXPECT_GT(worst_miss(linear), 1e-4);  // a cell is 1/64
}
