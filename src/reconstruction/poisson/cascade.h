// Internal: the cascadic solve. Coarse to fine, the screened energy is minimised over each depth's
// solved nodes, the band's boundary nodes holding the coarser depth's solution (a conforming
// finite-element space with hanging nodes), starting from the prolonged coarser solution.
#pragma once

#include <chrono>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "reconstruction/poisson/conjugate_gradients.h"
#include "reconstruction/poisson/normal_field.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"
#include "sdfcontour/reconstruction/poisson.h"

namespace sdfcontour::poisson {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// One depth's statistics: its unknowns counted from `solved`, the solver's state, the seconds
/// spent before the solve (prolongation, right-hand side, assembly) and since `solve_start`.
PoissonLevelStats level_stats(const OctreeLevel& L, const std::vector<char>& solved,
                              const CgState& state, double assembly_seconds,
                              Clock::time_point solve_start);

/// After the coarsest depth's solve: whether to solve again with Dirichlet boundaries, because
/// `boundary` is not Dirichlet, the fallback is on and far_field_inside(coarsest, x, points). If
/// so, sets boundary to Dirichlet and says so through the options' progress.
bool fall_back_to_dirichlet(const OctreeLevel& coarsest, const std::vector<double>& x,
                            const std::vector<UnitPoint>& points, const PoissonOptions& options,
                            PoissonBoundary& boundary);

/// Says through the options' progress that a depth stopped short of its tolerance, if it did.
void report_unconverged(const PoissonLevelStats& stats, bool finest, const PoissonOptions& options);

struct CascadeResult {
  std::vector<std::vector<double>> values;  ///< chi at each depth's nodes
  std::vector<PoissonLevelStats> levels;
  bool boundary_fallback = false;  ///< the far field came out inside; solved with Dirichlet
  /// The points' weighted mean of chi, when the solve evaluates chi more exactly than the node
  /// values' trilinear interpolation does (degree 2); NaN otherwise.
  double iso_value = std::numeric_limits<double>::quiet_NaN();
  /// chi at a unit-cube point, where the node values' trilinear interpolation is not chi
  /// (degree 2); empty otherwise.
  std::function<double(const Eigen::Vector3d&)> evaluate;
};

/// Whether more than 1% of the coarsest depth's face nodes are inside (chi >= the points' mean
/// chi at that depth, interpolated from the node values x).
bool far_field_inside(const OctreeLevel& coarsest, const std::vector<double>& x,
                      const std::vector<UnitPoint>& points);

/// Solves every depth. Consumes the normal field and the node columns level by level, so that
/// the finest solve runs with only what it needs in memory.
///
/// The normals point outward, so on the domain's faces chi must be outside (below the iso-value).
/// With Neumann (or free) boundaries chi's level there is set by the data alone; when the normals
/// nearly cancel (a thin plate sampled from both sides) it can end up level with the iso-value,
/// and the exterior fills with spurious sheets. This shows at the coarsest depth already (finer
/// depths do not change its values), so there the faces are checked against the points' mean chi,
/// and if more than 1% of them are inside, the depth is solved again with the faces pinned to
/// outside (Dirichlet), and so are all finer depths.
CascadeResult solve_coarse_to_fine(Octree& tree, NormalField& field,
                                   const std::vector<UnitPoint>& points, const MortonRuns& runs,
                                   double area_per_point, const PoissonOptions& options);

}  // namespace sdfcontour::poisson

namespace sdfcontour::poisson {

/// The same with degree-2 elements (quadratic_basis.h): coefficients on each depth's cells within
/// one of an active cell, prolonged exactly, and the finer splats' integrals restricted fine to
/// coarse. Returns chi at each depth's nodes (for the extraction) and the iso-value from chi
/// itself.
CascadeResult solve_coarse_to_fine_quadratic(Octree& tree, NormalField& field,
                                             const std::vector<UnitPoint>& points,
                                             const MortonRuns& runs, double area_per_point,
                                             const PoissonOptions& options);

}  // namespace sdfcontour::poisson
