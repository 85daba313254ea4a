// Screened Poisson surface reconstruction (Kazhdan, Bolitho & Hoppe 2006; Kazhdan & Hoppe 2013)
// of oriented points on an adaptive octree, with trilinear (degree-1) or quadratic (degree-2)
// B-spline elements.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// PoissonRecon's three boundary types. Neumann reflects the B-splines at the domain's faces
/// (even), Dirichlet reflects them oddly (chi = 0 there), free keeps every B-spline whose support
/// meets the domain, unmodified. For degree-1 elements an even reflection of a face node's hat only
/// rescales its part inside the domain, and no hat centred outside reaches inside, so Neumann and
/// free span the same space and give the same chi: the natural condition, dchi/dn = V.n. For
/// degree 2 they differ: Neumann's space holds only functions with dchi/dn = 0 on the faces, free's
/// also the B-splines centred just outside the domain, independent of those inside.
enum class PoissonBoundary {
  Neumann,    ///< reflected (even) B-splines; for degree 1, the natural condition
  Dirichlet,  ///< the indicator is 0 (outside) on the domain's faces
  Free,       ///< unmodified B-splines; for degree 1, the same space as Neumann
};

/// "neumann", "dirichlet", "free" <-> PoissonBoundary; parse throws Error for other names.
PoissonBoundary parse_poisson_boundary(const std::string& name);
std::string poisson_boundary_name(PoissonBoundary boundary);

struct PoissonOptions {
  int depth = 8;  ///< finest octree depth (the domain cube split 2^depth times)
  /// The elements: 1, trilinear (hats on the nodes); 2, quadratic B-splines on the cells' centres
  /// (PoissonRecon's default), smoother, with a 5 x 5 x 5 stencil and more unknowns per cell.
  int degree = 1;
  int full_depth = 5;             ///< the octree is complete down to this depth
  double scale = 1.1;             ///< domain cube = the points' bounding cube enlarged by this
  double samples_per_node = 1.5;  ///< splat each normal at the depth where a node holds this many
  double point_weight = 10.0;     ///< alpha, the screening weight (0: plain Poisson); see README
  PoissonBoundary boundary = PoissonBoundary::Neumann;
  /// Solve with Dirichlet boundaries instead when Neumann (or free) ones leave part of the
  /// domain's faces inside (see PoissonResult::boundary_fallback). Off for points of a surface
  /// known to leave the domain (a grid that cuts it), whose far field is inside in part.
  bool dirichlet_fallback = true;
  double solver_tolerance = 1e-4;  ///< conjugate gradients stop at this relative residual per depth
  /// ... except at the finest depth, which takes most of the solve's time: there this looser
  /// tolerance measured as accurate (L1 within ±1% on 28 grids, 32³-256³; docs/scale.md).
  double finest_solver_tolerance = 1e-3;
  int max_iterations = 200;  ///< and after this many iterations per depth (then: not converged)
  /// Each depth refines the cells around the points' cells within this many cells (1-4): the
  /// finer depth's edge nodes, which hold the coarser solution, stay that far from the points.
  /// 1 has ~40% fewer finest cells than 2 and a less accurate surface where points are sparse
  /// (wingnut at 100k points: L1 2.15e-4 against 1.71e-4); on GCP's dense contact points from
  /// 256^3 grids it cost 0.5-2.2% of the L1 for ~15% of the reconstruction's time. 0 (contour
  /// only): 2 below 256 samples per axis, 1 from 256.
  int refine_dilation = 2;
  /// Called with a short message as each stage starts; empty for silence.
  std::function<void(const std::string&)> progress;
  /// Called as the solve advances: ("poisson", cells of the depths solved, cells of all depths);
  /// cells weigh the depths as their cost does (the finest holds most). Empty for silence.
  std::function<void(const std::string&, long, long)> progress_fraction;
  /// When set and it becomes true, the reconstruction stops soon (at the next stage or solver
  /// iteration) by throwing Cancelled.
  const std::atomic<bool>* cancel = nullptr;
};

/// Per octree depth: size of the system solved there and how the solver fared.
struct PoissonLevelStats {
  int depth = 0;
  long cells = 0;     ///< active cells
  long unknowns = 0;  ///< nodes solved for (the rest hold the coarser solution)
  int iterations = 0;
  double relative_residual = 0;
  bool converged = false;  ///< the relative residual reached the solver tolerance
  double assembly_seconds = 0;
  double solve_seconds = 0;
};

struct PoissonResult {
  Mesh mesh;                       ///< watertight, outward oriented iso-surface
  Eigen::VectorXd vertex_density;  ///< per vertex: estimated samples per unit area around it
  double iso_value = 0;            ///< the indicator's average over the samples
  /// True when Neumann (or free) boundaries left part of the domain's faces inside at the coarsest
  /// depth (chi >= the points' mean chi there), which contradicts the outward normals, and the
  /// result comes from Dirichlet boundaries (the coarsest depth solved again, the rest with them).
  bool boundary_fallback = false;
  std::vector<PoissonLevelStats> levels;
  std::vector<std::pair<std::string, double>> seconds;  ///< per stage
  /// With SignedSamples: how many disagreed with chi (before correction) and after the last
  /// sweep (0 unless the sweeps ran out).
  long sign_violations = 0, sign_violations_left = 0;
  /// With SignedSamples: true when the corrected surface's topology (Euler characteristic,
  /// pieces) differed from the solved one's, so the solved one was kept.
  bool sign_constraints_dropped = false;
};

/// Samples whose side of the surface is known: value < 0 inside, > 0 outside, |value| their
/// distance to it (a signed distance's samples next to the surface).
struct SignedSamples {
  PointMatrix points;      ///< m x 3
  Eigen::VectorXd values;  ///< m signed distances
};

/// How the indicator is made to agree with SignedSamples before extraction.
struct SignConstraintOptions {
  /// Each sample must lie on its side with chi off the iso-value by at least
  /// margin * |value| * |grad chi| there (measured on the solved chi): 1 asks the surface to keep
  /// the sample's distance to the first order, 0 only its side.
  double margin = 1.0;
  /// A sample is corrected (to the full margin) only once chi is off the iso-value by less than
  /// trigger * margin * |value| * |grad chi| on its side: 1 corrects every sample short of the
  /// margin, 0 only samples on the wrong side.
  double trigger = 1.0;
  int max_sweeps = 20;  ///< passes over the samples (each sequential, so deterministic)
  /// A correction is a smooth bump of this radius (input units) around the sample, so that the
  /// surface moves past it; 0 changes only its cell's corners, which next to a coarse sampling
  /// punches a bubble around the sample instead.
  double radius = 0;
};

/// Why `points` (n x 3) make no surface for the screened Poisson solve: fewer than 4 of them, or
/// all at one place (the solve gave an empty mesh or a speck); empty where they can make one.
std::string poisson_no_surface(const PointMatrix& points);

/// Reconstructs a surface from points (n x 3) and normals (n x 3, any length > 0, outward).
/// Minimises  int |grad chi - V|^2 + alpha * (A/N) * 2^d * sum_i (chi(p_i) - 1/2)^2,
/// with V the normals splatted at adaptive depths (each weighted by its sample's area, A/N the
/// mean), solved coarse to fine, and extracts chi = (average of chi at the samples).
/// Throws Error for no points, NaN or infinite values, a zero normal, or points that make no
/// surface (poisson_no_surface).
PoissonResult poisson_reconstruct(const OrientedPoints& points, const PoissonOptions& options = {});

/// The same, then chi is corrected where `sides` disagree with it (see enforce_signs in
/// src/reconstruction/poisson/sign_constraints.h), so the extracted surface keeps the samples on
/// their sides; unless that changes the surface's topology
/// (PoissonResult::sign_constraints_dropped).
PoissonResult poisson_reconstruct(const OrientedPoints& points, const PoissonOptions& options,
                                  const SignedSamples& sides,
                                  const SignConstraintOptions& sign_options = {});

/// The same, taking the points: they are freed as soon as they are mapped into the solver's own
/// copy (at depth 10, a few hundred MB off the peak).
PoissonResult poisson_reconstruct(OrientedPoints&& points, const PoissonOptions& options,
                                  const SignedSamples& sides,
                                  const SignConstraintOptions& sign_options = {});

}  // namespace sdfcontour
