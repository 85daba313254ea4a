// The coarse-to-fine solve with degree-2 elements (cascade.h).
#include <chrono>
#include <cmath>
#include <sstream>

#include "reconstruction/poisson/bspline.h"
#include "reconstruction/poisson/cascade.h"
#include "reconstruction/poisson/conjugate_gradients.h"
#include "reconstruction/poisson/deterministic_sum.h"
#include "reconstruction/poisson/quadratic_basis.h"
#include "reconstruction/poisson/quadratic_system.h"

namespace sdfcontour::poisson {

namespace {

// The finer splats' integrals against each depth's B-splines, int grad B_c . V_{>=d}: a depth's
// own splats directly, the finer ones' restricted from the depth below. Every finer splat lies
// inside the finer depth's active cells, so the finer coefficient cells hold all that is nonzero.
std::vector<std::vector<double>> finer_integrals(const Octree& tree, const NormalField& field,
                                                 const std::vector<QuadraticCells>& cells,
                                                 const std::vector<QuadraticIntegrals>& tables) {
  std::vector<std::vector<double>> e(tree.levels.size());
  for (int d = tree.finest; d >= tree.min_depth; --d) {
    const std::size_t s = std::size_t(d);
    e[s].assign(cells[s].size(), 0.0);
    if (!field.splat_cells[s].keys.empty())
      quadratic_divergence(tree.level(d), cells[s], tables[s], field.splat_cells[s], field.splat[s],
                           e[s]);
    if (d < tree.finest) restrict_integrals(cells[s], cells[s + 1], e[s + 1], e[s]);
  }
  return e;
}

// The coefficient cells of every depth for a boundary.
std::vector<QuadraticCells> all_cells(const Octree& tree, PoissonBoundary boundary) {
  std::vector<QuadraticCells> cells(tree.levels.size());
  for (int d = tree.min_depth; d <= tree.finest; ++d)
    cells[std::size_t(d)] = quadratic_cells(tree.level(d), boundary);
  return cells;
}

}  // namespace

CascadeResult solve_coarse_to_fine_quadratic(Octree& tree, NormalField& field,
                                             const std::vector<UnitPoint>& points,
                                             const MortonRuns& runs, double area_per_point,
                                             const PoissonOptions& o) {
  CascadeResult result;
  result.values.resize(tree.levels.size());
  PoissonBoundary boundary = o.boundary;
  std::vector<QuadraticCells> cells = all_cells(tree, boundary);
  std::vector<QuadraticIntegrals> tables;
  for (std::size_t d = 0; d < tree.levels.size(); ++d)
    tables.emplace_back(d >= std::size_t(tree.min_depth) ? tree.levels[d].res : 0);
  std::vector<std::vector<double>> finer = finer_integrals(tree, field, cells, tables);
  std::vector<std::vector<double>> x(tree.levels.size());
  // V from coarser splats on the current depth's spline grid (quadratic B-splines nest).
  std::vector<Eigen::Vector3d> coarser;
  CellGrid grid, coarser_grid;
  const CgOptions cg{o.solver_tolerance, o.max_iterations, o.cancel},
      cg_finest{o.finest_solver_tolerance, o.max_iterations, o.cancel};
  for (int d = tree.min_depth; d <= tree.finest; ++d) {
    const auto level_start = Clock::now();
    const std::size_t s = std::size_t(d);
    const OctreeLevel& L = tree.level(d);
    grid = spline_grid(L);
    coarser = d == tree.min_depth
                  ? std::vector<Eigen::Vector3d>(grid.keys.size(), Eigen::Vector3d::Zero())
                  : prolong_splines(coarser_grid, grid, coarser);
    std::vector<double> divergence = std::move(finer[s]);
    quadratic_divergence(L, cells[s], tables[s], grid, coarser, divergence);
    const double screening = o.point_weight * area_per_point * std::ldexp(1.0, d);
    const double prolong_seconds = seconds_since(level_start);
    auto solve = [&]() {
      const auto start = Clock::now();
      const QuadraticCells& C = cells[s];
      x[s] = d == tree.min_depth ? std::vector<double>(C.size(), 0.0)
                                 : prolong_coefficients(cells[s - 1], C, x[s - 1]);
      QuadraticSystem system = assemble_quadratic_system(L, C, tables[s], divergence, field.runs[s],
                                                         screening, points, runs);
      const double assembly = seconds_since(start);
      const auto solve_start = Clock::now();
      std::vector<double> b = std::move(system.b);
      const CgState state = conjugate_gradients(
          C.size(), C.solved, std::move(b),
          [&](const std::vector<double>& in, std::vector<double>& out) {
            return multiply(system, in, out);
          },
          [&](std::size_t c) { return system.diagonal[c]; }, x[s],
          d == tree.finest ? cg_finest : cg);
      apply_ties(C, x[s]);
      return level_stats(L, C.solved, state, prolong_seconds + assembly, solve_start);
    };
    PoissonLevelStats stats = solve();
    result.values[s] = node_values(L, cells[s], x[s]);
    if (d == tree.min_depth && fall_back_to_dirichlet(L, result.values[s], points, o, boundary)) {
      result.boundary_fallback = true;
      // The cells stay; only their ties and unknowns follow the boundary (the finer integrals,
      // against untied B-splines, hold).
      for (int e = tree.min_depth; e <= tree.finest; ++e)
        tie_to_boundary(tree.level(e), boundary, cells[std::size_t(e)]);
      stats = solve();
      result.values[s] = node_values(L, cells[s], x[s]);
    }
    add_on_grid(field.splat_cells[s], field.splat[s], grid, coarser);
    coarser_grid = std::move(grid);
    report_unconverged(stats, d == tree.finest, o);
    result.levels.push_back(stats);
  }
  // chi at a point: from the finest depth whose active cell holds it (the coefficients are kept
  // for the extraction's edges).
  struct Coefficients {
    std::vector<QuadraticCells> cells;
    std::vector<std::vector<double>> x;
  };
  auto kept = std::make_shared<Coefficients>(Coefficients{std::move(cells), std::move(x)});
  const Octree& octree = tree;
  auto chi = [kept, &octree](const Eigen::Vector3d& p) {
    for (int d = octree.finest; d >= octree.min_depth; --d) {
      const OctreeLevel& L = octree.level(d);
      const auto c = cell_of(p, L.res);
      if (L.cell(pack(c[0], c[1], c[2])) >= 0)
        return evaluate(L, kept->cells[std::size_t(d)], kept->x[std::size_t(d)], c, p);
    }
    return 0.0;
  };
  result.evaluate = chi;
  result.iso_value =
      deterministic_sum(points.size(),
                        [&](std::size_t q) { return points[q].weight * chi(points[q].p); }) /
      deterministic_sum(points.size(), [&](std::size_t q) { return points[q].weight; });
  return result;
}

}  // namespace sdfcontour::poisson
