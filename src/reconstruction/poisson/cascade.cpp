#include "reconstruction/poisson/cascade.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "reconstruction/free_memory.h"
#include "reconstruction/poisson/bspline.h"
#include "reconstruction/poisson/conjugate_gradients.h"
#include "reconstruction/poisson/deterministic_sum.h"
#include "reconstruction/poisson/indicator.h"
#include "reconstruction/poisson/system.h"

namespace sdfcontour::poisson {

PoissonLevelStats level_stats(const OctreeLevel& L, const std::vector<char>& solved,
                              const CgState& state, double assembly_seconds,
                              Clock::time_point solve_start) {
  long unknowns = 0;
  for (char u : solved) unknowns += u;
  return PoissonLevelStats{L.depth,          long(L.cells.size()),      unknowns,
                           state.iterations, state.relative_residual,   state.converged,
                           assembly_seconds, seconds_since(solve_start)};
}

bool fall_back_to_dirichlet(const OctreeLevel& coarsest, const std::vector<double>& x,
                            const std::vector<UnitPoint>& points, const PoissonOptions& o,
                            PoissonBoundary& boundary) {
  if (boundary == PoissonBoundary::Dirichlet || !o.dirichlet_fallback ||
      !far_field_inside(coarsest, x, points))
    return false;
  boundary = PoissonBoundary::Dirichlet;
  if (o.progress)
    o.progress("poisson: the far field came out inside; solving again with Dirichlet boundaries");
  return true;
}

void report_unconverged(const PoissonLevelStats& stats, bool finest, const PoissonOptions& o) {
  if (stats.converged || !o.progress) return;
  std::ostringstream message;
  message << "poisson: depth " << stats.depth << " stopped at relative residual "
          << stats.relative_residual << " after " << stats.iterations << " iterations (tolerance "
          << (finest ? o.finest_solver_tolerance : o.solver_tolerance) << ")";
  o.progress(message.str());
}

bool far_field_inside(const OctreeLevel& C, const std::vector<double>& x,
                      const std::vector<UnitPoint>& points) {
  const double iso =
      deterministic_sum(points.size(),
                        [&](std::size_t s) {
                          return interpolate(C, x, cell_of(points[s].p, C.res), points[s].p);
                        }) /
      double(points.size());
  long inside = 0, count = 0;
  for (std::size_t v = 0; v < C.nodes.size(); ++v) {
    const auto [i, j, k] = unpack(C.nodes[v]);
    if (C.on_face(i, j, k)) inside += x[v] >= iso, ++count;
  }
  return inside * 100 > count;
}

CascadeResult solve_coarse_to_fine(Octree& tree, NormalField& field,
                                   const std::vector<UnitPoint>& points, const MortonRuns& runs,
                                   double area_per_point, const PoissonOptions& o) {
  CascadeResult result;
  result.values.resize(tree.levels.size());
  PoissonBoundary boundary = o.boundary;
  const CgOptions cg{o.solver_tolerance, o.max_iterations, o.cancel},
      cg_finest{o.finest_solver_tolerance, o.max_iterations, o.cancel};
  // V from coarser splats, expressed on the current depth's spline grid (quadratic B-splines
  // nest), and the coarser depth's grid it was prolonged from. The two finest depths never build
  // their grids (the largest arrays of a reconstruction): V stays on a coarser depth's grid and
  // their hats are integrated against its B-splines (splat_divergence_from_coarser).
  std::vector<Eigen::Vector3d> coarser;
  CellGrid grid, coarser_grid;
  // The finest depth's solved nodes and right-hand side, made before the depth before the finest
  // is solved, so that the coarser splats are freed by then.
  std::vector<char> finest_solved;
  std::vector<double> finest_b;
  long cells_total = 0, cells_done = 0;
  for (int d = tree.min_depth; d <= tree.finest; ++d)
    cells_total += long(tree.level(d).cells.size());
  if (o.progress_fraction) o.progress_fraction("poisson", 0, cells_total);
  for (int d = tree.min_depth; d <= tree.finest; ++d) {
    const auto level_start = Clock::now();
    OctreeLevel& L = tree.level(d);
    auto& x = result.values[std::size_t(d)];
    // The two finest depths take V's divergence from a coarser depth's grid.
    const bool from_coarser = d >= tree.finest - 1 && d > tree.min_depth;
    if (!from_coarser) grid = spline_grid(L);
    if (d == tree.min_depth) {
      coarser.assign(grid.keys.size(), Eigen::Vector3d::Zero());
    } else {
      x = prolong_values(tree.level(d - 1), L, result.values[std::size_t(d - 1)]);
      if (!from_coarser) coarser = prolong_splines(coarser_grid, grid, coarser);
    }
    if (!from_coarser) coarser_grid = CellGrid();
    const double screening = o.point_weight * area_per_point * std::ldexp(1.0, d);
    // Once this depth's right-hand side holds the normal field: pass this depth's splats on to
    // the next depth's field and free what the next depths do not need (before the rows are
    // built and the system solved, the largest at the end).
    auto release_field = [&]() {
      if (d < tree.finest) {
        // This depth's splats join V: on this depth's grid, or, when V stayed on the coarser
        // grid, added slab by slab as the finest depth's right-hand side prolongs it.
        const MiddleDepth middle{L, field.splat_cells[std::size_t(d)], field.splat[std::size_t(d)]};
        if (!from_coarser) {
          add_on_grid(middle.splat_cells, middle.splat, grid, coarser);
          coarser_grid = std::move(grid);
        }
        if (d + 1 == tree.finest) {
          const OctreeLevel& F = tree.level(tree.finest);
          finest_solved = solved_nodes(F, boundary);
          finest_b = splat_divergence_from_coarser(F, finest_solved, coarser_grid, coarser,
                                                   std::move(field.finer[std::size_t(tree.finest)]),
                                                   from_coarser ? &middle : nullptr);
          std::vector<Eigen::Vector3d>().swap(coarser);
          coarser_grid = CellGrid();
        }
      } else {
        std::vector<Eigen::Vector3d>().swap(coarser);
        coarser_grid = CellGrid();
      }
      grid = CellGrid();
      field.splat_cells[std::size_t(d)] = CellGrid();
      std::vector<Eigen::Vector3d>().swap(field.splat[std::size_t(d)]);
      std::vector<double>().swap(field.finer[std::size_t(d)]);
    };
    // Assembles and solves this depth with the current boundary; returns its statistics. The
    // coarsest depth keeps its terms for a second solve (see below).
    const double prolong_seconds = seconds_since(level_start);
    auto solve = [&](std::vector<char>& solved) {
      const auto start = Clock::now();
      if (d == tree.min_depth) x.assign(L.nodes.size(), 0.0);
      std::vector<double> b;
      if (from_coarser && d == tree.finest) {  // made at the depth before
        solved = std::move(finest_solved);
        b = std::move(finest_b);
      } else {
        solved = solved_nodes(L, boundary);
        // The finer splats' part becomes the right-hand side; the coarsest depth may solve twice.
        auto& finer_part = field.finer[std::size_t(d)];
        std::vector<double> finer = d == tree.min_depth ? finer_part : std::move(finer_part);
        b = from_coarser
                ? splat_divergence_from_coarser(L, solved, coarser_grid, coarser, std::move(finer))
                : splat_divergence(L, solved, grid, coarser, std::move(finer));
      }
      if (d > tree.min_depth) release_field();
      detail::return_free_memory();
      LevelSystem system = assemble_system(L, solved, std::move(b), field.runs[std::size_t(d)],
                                           screening, points, runs);
      if (d > tree.min_depth) field.runs[std::size_t(d)] = CellRuns();
      const double assembly = seconds_since(start);
      detail::return_free_memory();
      const auto solve_start = Clock::now();
      const CgState state =
          conjugate_gradients(L, solved, std::move(system), x, d == tree.finest ? cg_finest : cg);
      return level_stats(L, solved, state, prolong_seconds + assembly, solve_start);
    };
    std::vector<char> solved;
    PoissonLevelStats stats = solve(solved);
    if (d == tree.min_depth) {
      if (fall_back_to_dirichlet(L, x, points, o, boundary)) {
        result.boundary_fallback = true;
        stats = solve(solved);
      }
      release_field();
      field.runs[std::size_t(d)] = CellRuns();
    }
    report_unconverged(stats, d == tree.finest, o);
    result.levels.push_back(stats);
    cells_done += long(L.cells.size());
    if (o.progress_fraction) o.progress_fraction("poisson", cells_done, cells_total);
  }
  return result;
}

}  // namespace sdfcontour::poisson
