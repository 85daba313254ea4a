// contour()'s local reconstruction stage: GCP's mesh brick by brick from the grid (local_brick.h),
// each brick making its own contact points or taking the whole grid's (GTCP's exact ones, other
// gradients', every sample's).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "pipeline/pipeline_stages.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour {

// The local reconstruction's contact points (the Poisson path keeps the paper's). The values
// below were chosen on the shared meshes' L1 over marching cubes' at 32^3 and 64^3; measure again
// with `bench/local.py --res 32,64 --methods mc,gcp-local` (docs/notes/local.md has the sweeps).
//
// No point from a sample whose neighbours miss its gradient's linear prediction by more than 0.45
// of its distance (across a crease or a medial axis); discarded points slide over their sphere out
// of the neighbours' (50 rounds), which finds convex edges and corners (64^3: 0.365x -> 0.343x MC's
// L1; 0.3, 0.6 and 0.8 were worse).
constexpr double kLocalSlopeMiss = 0.45;
constexpr int kLocalSlideRounds = 50;
// Samples still without a point take a vertex of their power cell on their sphere (power within
// 3e-4 value^2 of zero): the box's corners exactly, and where a sphere is nearly covered (64^3:
// 0.343x -> 0.291x MC's L1; 1e-3 left a sample 0.05 h on the wrong side, 1e-4 and 1e-2 were worse).
constexpr double kLocalPowerVertex = 3e-4;
// A candidate that a neighbour's sphere holds less than 3e-3 of its |value| deep is kept: on smooth
// shapes those are a few thousandths of a spacing off, the power vertices that would replace them
// 0.016 h. At 1e-3 the analytic torus at 64^3 kept power vertices on its mirror planes and its
// worst vertex went beyond marching cubes' (bench/smooth_shapes.py).
constexpr double kLocalNearMiss = 3e-3;
// The lattice's contact points slide for fewer rounds: each round searches every sphere in reach
// (the triangulation's, its neighbours only). Bunny 32^3: 10 rounds rescue 1,480 points in 0.49 s,
// 50 rounds 2,733 in 1.49 s, at the same median distance (bench/lattice_points.py --res 32).
constexpr int kLatticeSlideRounds = 10;
// The lattice's rescues only for samples within 5 spacings of the surface: beyond, each slide
// and power cell reads 200-270 spheres (band 8), 59% of the rescues' time at bunny 64^3 for 9% of
// its points. Against rescues at every depth, the shared meshes' L1 is 1.006x / 1.003x / 1.012x
// at 64^3 / 128^3 / 256^3 (worst 1.027x, 1.010x, 1.019x; 4 spacings: 1.009x, 1.008x, 1.019x) and
// bunny's contact points take 0.52x / 0.84x / 0.92x the time (docs/results/speed_s53.md).
constexpr double kLatticeRescueReach = 5;
// Edge fans on the grid itself fit their projection once, with no refit: a refit moved the L1 of
// bunny, spot and armadillo with fans at band 3 by 0.1-1.6% either way at 64^3-256^3, bunny's at
// 512^3 by 0.5%, and the shared meshes' at 32^3 and 64^3 by 0.2% on average (the torus at 64^3
// 11%), for a fifth of the projection's time (docs/results/fan_rounds_s69.md). On the finer grid,
// as in the default, two pay: the torus at 64^3 lost 4% with one.
constexpr int kFanRobustRounds = 0;
// Edge fans on the grid itself place their cells' vertices without reweighting the planes: the
// reweighting, at 0.01 spacings, pulls a smooth patch's vertex along its plane towards the points
// that agree most, and the fans keep that layout (projection moves a vertex along its normal
// only). L1 without it, fans at band 3: bunny, spot, armadillo at 128^3 0.89x / 0.97x / 0.96x,
// 256^3 0.82x / 0.91x / 0.91x, 512^3 0.78x / 0.85x / 0.82x; with the single fit, the shared
// meshes at 384^3 0.84x (none worse by 0.3%; the torus 0.61x), their sharp-edge distances 1.02x
// (penguin 1.07x). The default's subdivided mesh moves by 1-3% either way: it keeps three rounds.
constexpr int kFanCellRobustRounds = 0;
// Edge fans carve no vertex (the samples' spheres still bound their edges' vertices as those are
// placed): carving is a repair the fans' regions do not need. Bunny 512^3 0.92x the time (the
// stage 0.98 -> 0.18 s), L1 +1.4% (spot +0.9%, armadillo +2.2%, every L-inf under marching
// cubes'); bunny 384^3 0.90x, +1.2%; --edge-fans on at 64^3 0.83x, +1.8% (docs/edge_fans.md).
constexpr int kFanCarvePasses = 0;

LocalBrickOptions local_brick_options(const ContourOptions& options) {
  LocalBrickOptions lb;
  lb.band = options.band;
  lb.gradient = options.gradient;
  lb.lattice_points = options.gradient_source == GradientSource::Lattice   ? 1
                      : options.gradient_source == GradientSource::Regular ? 0
                                                                           : -1;
  lb.contact = options.contact;
  lb.contact.max_slope_miss = kLocalSlopeMiss;
  lb.contact.try_tet_gradients = false;  // (the slide, below, rescues those points)
  lb.contact.sphere_slide_rounds = kLocalSlideRounds;
  lb.contact.power_vertex_tolerance = kLocalPowerVertex;
  lb.contact.near_miss_tolerance = kLocalNearMiss;
  lb.lattice_contact = lb.contact;
  lb.lattice_contact.sphere_slide_rounds = kLatticeSlideRounds;
  lb.lattice_contact.rescue_reach = kLatticeRescueReach;
  lb.lattice_contact.tie_tolerance = options.lattice_tie_tolerance;
  lb.local = options.local;
  if (lb.local.robust_rounds == kAutoRobustRounds)
    lb.local.robust_rounds = LocalReconstructionOptions{}.robust_rounds;
  lb.subdivisions = options.subdivisions;
  lb.split_sag = options.split_sag;
  lb.thin_parts = options.thin_parts == Switch::On ? 1 : options.thin_parts == Switch::Off ? 0 : -1;
  lb.project = options.project != Switch::Off;
  lb.projection = options.local_projection;
  if (lb.projection.robust_rounds == kAutoRobustRounds)
    lb.projection.robust_rounds = local_projection_options().robust_rounds;
  lb.carve = options.carve != Switch::Off;
  lb.carve_passes = options.carving.passes;
  lb.refine_zero_set = options.zero_set == Switch::On;
  lb.zero_set = options.zero_set_options;
  lb.cancel = options.cancel;
  if (options.local.edge_fans) {  // right by construction: nothing to repair
    lb.untangle = false;
    lb.side_rounds = 0;
    // The finer grid only when asked: about 4x the fans' triangles (docs/edge_fans.md).
    if (options.thin_parts != Switch::On) lb.thin_parts = 0;
    if (lb.thin_parts == 0 && options.local_projection.robust_rounds == kAutoRobustRounds)
      lb.projection.robust_rounds = kFanRobustRounds;
    if (lb.thin_parts == 0 && options.local.robust_rounds == kAutoRobustRounds)
      lb.local.robust_rounds = kFanCellRobustRounds;
    lb.carve_passes = kFanCarvePasses;
  }
  return lb;
}

}  // namespace sdfcontour

namespace sdfcontour::detail {

bool bricked_local(const GridView* grid, const ContourOptions& options) {
  // Bricks need a band: with every sample (--band all), one sphere can reach across the grid.
  if (!grid || options.method != Method::Gcp || !options.want_mesh ||
      !local_gradients(options.gradient_source) || !std::isfinite(options.band.band))
    return false;
  return options.reconstruction == Reconstruction::Local ||
         (options.reconstruction == Reconstruction::Auto &&
          auto_local_reconstruction(*std::max_element(grid->dims.begin(), grid->dims.end())));
}

namespace {

// The subspacing gaps of a grid in memory (parallel, windowed over a mapped file).
SubspacingGaps subspacing_gaps_of(const GridView& grid, double value_scale) {
  return count_subspacing_gaps(grid, value_scale);
}

// ... of a grid read a block at a time, in the bricks that its local reconstruction reads.
SubspacingGaps subspacing_gaps_of(const BlockedGrid& grid, double value_scale) {
  return count_subspacing_gaps(grid, value_scale, kLocalBrick);
}

bool truncation_found(const GridView& grid, const BandOptions& band) {
  return resolve_truncation(grid, band).detected();
}
bool truncation_found(const BlockedGrid&, const BandOptions& band) {
  return resolve_truncation(Eigen::VectorXd(), band).detected();  // given, never found
}

// One brick up to 512 samples per axis for a grid in memory (its stages run in parallel inside
// it), bricks of 512 beyond; with edge fans, whose halo is a cell or two, not the repairs' ~55
// samples, bricks of 256 (kLocalBrick). A grid read block by block, which exists to bound
// memory, bricks of 256 (as a callable's or Dask's).
int default_brick(const GridView&, const ContourOptions& options) {
  return options.local.edge_fans ? kLocalBrick : kLocalGridBrick;
}
int default_brick(const BlockedGrid&, const ContourOptions&) {
  return kLocalBrick;
}

// After the bricks made their own contact points: says (or throws, as asked) where few or none
// kept a point; hands on the kept ones (`kept`).
template <class AnyGrid>
void check_contact_points(const AnyGrid& grid, const BandOptions& band, const LocalBrickOptions& lb,
                          const LocalBricksStats& stats, const ContourOptions& options,
                          OrientedPoints& kept, ContourResult& result) {
  // Each cell decides for itself: one with contact points nearby takes GCP's vertex, one without
  // keeps its edge crossings' (or, where the values are no distances, the zero set's). A grid
  // where few or none keep a point is said, and is no error unless asked (fallback_to_mc off);
  // nothing runs again. (Rescaled values that hide nearly every point were no scaled distances:
  // hammer 32^3 rescaled by 1.11 gave 0.62x MC's L1, 0.27x as given, which
  // GradientNormSummary::slope now keeps.)
  std::string few;
  if (stats.contact_points == 0 && !lb.refine_zero_set) {
    // A band the user narrowed is the user's error.
    if (band.band > 0 && !truncation_found(grid, band))
      throw Error("no contact point: no sample within the band of " +
                  (std::ostringstream() << band.band).str() +
                  " spacings keeps one; widen it with --band (or --band all)");
    few = kNoContactPoint;
  } else if (band.value_scale != 1 && 10 * stats.contact_points < stats.local.cells) {
    few = "only " + std::to_string(stats.contact_points) + " contact points for " +
          std::to_string(stats.local.cells) + " cells crossing the surface";
  }
  say_cells_from_crossings(few, options);
  if (lb.keep_contact_points) {
    ContactPoints cp;
    cp.points = std::move(kept.points);
    cp.normals = std::move(kept.normals);
    result.contact_points = std::move(cp);
  }
}

// `given` (optional): the whole grid's contact points, made and checked by the caller
// (result.contact_points holds them); the bricks take theirs from it.
template <class AnyGrid>
void reconstruct_grid_in_bricks(const AnyGrid& grid, const BandOptions& band,
                                const ContourOptions& given_options, ContourResult& result,
                                Stages& stages, const std::function<void()>& grid_read,
                                const GivenContactPoints* given = nullptr) {
  if (given_options.carve_sides == Switch::On || given_options.side_repair == Switch::On)
    throw Error(
        "carving's triangle rounds and side repair are whole-mesh stages: the local "
        "reconstruction runs brick by brick and carves vertex by vertex (--side-passes 0, or "
        "--reconstruction poisson)");
  const double samples_per_axis = *std::max_element(grid.dims.begin(), grid.dims.end());
  const ContourOptions options = with_edge_fans(given_options, samples_per_axis);
  LocalBrickOptions lb = local_brick_options(options);
  lb.band = band;
  lb.grid_read = grid_read;
  // Thin parts on fine grids only where the grid has them: one pass over the values, before the
  // bricks, which must agree (none beyond kThinPartGridLimit: thin parts stay off there).
  if (lb.thin_parts < 0 && !lb.refine_zero_set && thin_parts_need_gaps(samples_per_axis)) {
    result.subspacing_gaps = stages.run("gaps", "edges with a thin part across",
                                        [&] { return subspacing_gaps_of(grid, band.value_scale); });
    lb.thin_parts = auto_thin_parts(samples_per_axis, *result.subspacing_gaps) ? 1 : 0;
  }
  if (options.progress_fraction)
    lb.progress = [&](int done, int total) { options.progress_fraction("bricks", done, total); };
  // With every sample (band 'all') any sphere may reach across the grid: one brick.
  const int size = !std::isfinite(band.band)                        ? 0
                   : options.bricks.size == BrickOptions::kAutoSize ? default_brick(grid, options)
                                                                    : options.bricks.size;
  LocalBricksStats stats;
  // Adaptivity merges over the contact points, and --points writes the ones the mesh was made
  // from (the local reconstruction's options differ from the paper's): the bricks hand theirs on.
  lb.given_points = given;
  lb.keep_contact_points = !given && (options.adaptivity.tolerance > 0 || options.want_points);
  OrientedPoints kept;
  result.mesh = stages.run("local", "local reconstruction in bricks", [&] {
    return local_mesh_in_bricks(grid, lb, size, &stats, lb.keep_contact_points ? &kept : nullptr);
  });
  if (!given) check_contact_points(grid, band, lb, stats, options, kept, result);
  result.local = stats.local;
  for (std::size_t k = 0; k < stats.seconds.size(); ++k)
    result.local_stages.push_back({kLocalSteps[k], stats.seconds[k]});
  result.local_bricks = stats;
  result.edge_fans = options.local.edge_fans;
  result.reconstruction = Reconstruction::Local;
  result.band_spacing = grid.spacing().maxCoeff();
  if (result.mesh->triangles.rows() == 0)
    throw Error("the local reconstruction found no surface inside the grid");
}

}  // namespace

void say_cells_from_crossings(const std::string& few, const ContourOptions& options) {
  if (few.empty()) return;
  if (!options.fallback_to_mc) throw Error(few + ": the values do not behave as distances");
  if (options.progress)
    options.progress(few +
                     ": the cells without one take their vertex from their edge crossings, as dual "
                     "contouring does");
}

void reconstruct_in_bricks(const GridView& grid, const BandOptions& band,
                           const ContourOptions& options, ContourResult& result, Stages& stages,
                           const std::function<void()>& grid_read) {
  reconstruct_grid_in_bricks(grid, band, options, result, stages, grid_read);
}

void reconstruct_in_bricks(const BlockedGrid& grid, const BandOptions& band,
                           const ContourOptions& options, ContourResult& result, Stages& stages) {
  reconstruct_grid_in_bricks(grid, band, options, result, stages, {});
}

void reconstruct_from_points(const GridView& grid, const BandOptions& band,
                             const GivenContactPoints& points, const ContourOptions& options,
                             ContourResult& result, Stages& stages) {
  reconstruct_grid_in_bricks(grid, band, options, result, stages, {}, &points);
}

}  // namespace sdfcontour::detail
