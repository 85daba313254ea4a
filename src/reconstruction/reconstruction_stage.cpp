// contour()'s mesh from contact points (gcp, gtcp): screened Poisson reconstruction, then GCP's
// projection, carving and untangling, and the checks that the values were distances.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

#include "pipeline/pipeline_stages.h"
#include "sdfcontour/band/point_clusters.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/metrics/field_agreement.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/reconstruction/zero_set_refinement.h"

namespace sdfcontour::detail {

namespace {

// On exact distances (51 grids: the shared meshes at 16^3, 32^3, 64^3) no vertex is that far off;
// on a torus implicit (x^2+y^2+z^2+R^2-r^2)^2 - 4R^2(x^2+y^2) at 64^3, 28% are.
constexpr double kMostOffZeroSet = 0.01;

// Contact points this many spacings apart (and farther) belong to separate Poisson solves.
constexpr double kClusterGap = 16;

// GCP's mesh must lie on the field's zero set: more than 1% of its vertices a spacing or more
// off it means the contact points were not on the surface (a smooth implicit whose gradient norm
// varies along the surface passes the other checks, then makes a mesh of ~2000 pieces).
void check_on_zero_set(const GridSource& grid, ContourResult& result) {
  const double h = grid.geometry().spacing().maxCoeff();
  result.off_zero_set = grid.fraction_off_zero_set(*result.mesh, h, result.value_scale);
  if (result.off_zero_set > kMostOffZeroSet) {
    std::ostringstream message;
    message << std::setprecision(3) << 100 * result.off_zero_set
            << "% of the mesh's vertices lie more than a spacing off the field's zero set";
    result.fallback = message.str();
    return;
  }
  // Nor more pieces than marching cubes finds in the same field: the extra ones are bubbles
  // around contact points that strayed (noise of 0.5 h, smoothed, left 6 on a torus).
  // Marching cubes finds at least one piece in a field with a sign change, so it runs (on the
  // whole grid) only when GCP's mesh has more.
  const int pieces = connected_components(*result.mesh);
  if (pieces <= 1) return;
  const int mc_pieces = connected_components(grid.marching_cubes());
  if (pieces > mc_pieces)
    result.fallback = "the mesh has " + std::to_string(pieces) +
                      " connected pieces where marching cubes finds " + std::to_string(mc_pieces);
}

// The band's own samples within `reach` of the surface, whose sides the indicator keeps.
SignedSamples samples_near_surface(const BandSamples& band, double reach) {
  const Samples& s = band.samples;
  std::vector<Eigen::Index> near;
  for (Eigen::Index i = 0; i < s.values.size(); ++i)
    if (band.core[std::size_t(i)] && std::abs(s.values[i]) <= reach) near.push_back(i);
  Samples picked = samples_at(s, near);
  return SignedSamples{std::move(picked.points), std::move(picked.values)};
}

// The reconstruction of result.contact_points into result.mesh. The points and normals go to
// the reconstruction rather than a copy of them (at 512^3, 180 MB): freed there once mapped into
// its own copy unless asked for, else given back.
void add_poisson_result(PoissonResult&& p, ContourResult& result) {
  if (!result.mesh) result.mesh.emplace();
  append_mesh(*result.mesh, p.mesh);
  result.sign_violations += p.sign_violations;
  result.sign_violations_left += p.sign_violations_left;
  result.sign_constraints_dropped |= p.sign_constraints_dropped;
  for (const auto& [name, seconds] : p.seconds) result.poisson_stages.push_back({name, seconds});
}

// One screened Poisson solve per cluster of contact points (point_clusters): objects far apart in
// a scene each get an octree over their own extent, instead of one octree whose cells are
// larger than they are. One cluster is the plain, single solve.
void poisson_stage(ReconstructionInputs& in, const ContourOptions& options, ContourResult& result,
                   Stages& stages) {
  ContactPoints& lent = *result.contact_points;
  const std::string count = std::to_string(lent.size());
  SignConstraintOptions sopt = options.sign_constraints;
  sopt.radius = options.sign_radius * result.band_spacing;
  const double cell = kClusterGap * result.band_spacing;
  const std::vector<int> cluster = point_clusters(lent.points, cell);
  const int clusters = cluster.empty() ? 0 : *std::max_element(cluster.begin(), cluster.end()) + 1;
  result.mesh.reset();
  result.sign_violations = result.sign_violations_left = 0;
  if (clusters <= 1) {
    OrientedPoints oriented{std::move(lent.points), std::move(lent.normals), {}};
    PoissonResult p =
        stages.run("poisson", "screened Poisson reconstruction of " + count + " points", [&] {
          if (!options.want_points && !in.project && !(options.adaptivity.tolerance > 0))
            return poisson_reconstruct(std::move(oriented), in.poisson, in.sides, sopt);
          return poisson_reconstruct(oriented, in.poisson, in.sides, sopt);
        });
    lent.points = std::move(oriented.points);
    lent.normals = std::move(oriented.normals);
    add_poisson_result(std::move(p), result);
    return;
  }
  stages.run(
      "poisson",
      "screened Poisson reconstruction of " + count + " points in " + std::to_string(clusters) +
          " separate clusters",
      [&] {
        int deepest = 0;
        for (int c = 0; c < clusters; ++c) {
          OrientedPoints part;
          std::vector<int> rows;
          for (std::size_t r = 0; r < cluster.size(); ++r)
            if (cluster[r] == c) rows.push_back(int(r));
          part.points = lent.points(rows, Eigen::all);
          part.normals = lent.normals(rows, Eigen::all);
          if (!poisson_no_surface(part.points).empty()) continue;  // a cluster without one
          // The sides that matter: samples near this cluster's points.
          const Eigen::AlignedBox3d box(
              part.points.colwise().minCoeff().transpose().array() - cell,
              part.points.colwise().maxCoeff().transpose().array() + cell);
          std::vector<int> near;
          for (Eigen::Index s = 0; s < in.sides.points.rows(); ++s)
            if (box.contains(in.sides.points.row(s).transpose())) near.push_back(int(s));
          const SignedSamples sides{in.sides.points(near, Eigen::all), in.sides.values(near)};
          PoissonOptions popt = in.poisson;
          if (in.auto_depth) popt.depth = auto_poisson_depth(part.points, result.band_spacing);
          deepest = std::max(deepest, popt.depth);
          add_poisson_result(poisson_reconstruct(part, popt, sides, sopt), result);
        }
        result.poisson_depth = deepest;
        return 0;
      });
}

// A surface that runs out of the grid (a cropped scan's TSDF) ends at its sides, as marching
// cubes' does; the reconstruction closed it outside, where no sample was.
void clip_to_grid(const GridSource& grid, const ContourOptions& options, ContourResult& result) {
  if (options.method != Method::Gcp || !grid) return;
  const Bounds& box = grid.geometry().bounds;
  result.clipped_to_grid |= clip_mesh_to_box(*result.mesh, box.min, box.max);
  if (result.mesh->triangles.rows() == 0)
    result.fallback = "no part of the reconstructed surface lies in the grid";
}

// Projection and carving move vertices by a fraction of a spacing, which can push a thin part's
// sheet through the other; such moves are undone, the reconstruction's own mesh being free of
// crossings.
void untangle(const PointMatrix& before, ContourResult& result, Stages& stages) {
  const UntangleStats u = stages.run("untangling", "undoing moves that cross the mesh", [&] {
    return revert_self_intersections(*result.mesh, before, 0, nullptr,
                                     stages.fraction("untangling"));
  });
  UntangleStats& sum = result.untangling.emplace(result.untangling.value_or(UntangleStats{}));
  sum.rounds += u.rounds;
  sum.vertices_reverted += u.vertices_reverted;
  sum.intersections_found += u.intersections_found;
  sum.intersections_left += u.intersections_left;
}

}  // namespace

// GCP's moves after the reconstruction: onto the contact points, out of the samples' spheres,
// each undone where it made the mesh cross itself.
void refine_stage(const ReconstructionInputs& in, const ContourOptions& options,
                  ContourResult& result, Stages& stages) {
  const ContactPoints& cp = *result.contact_points;
  // Where carving moves vertices only (no side passes, from 128 samples per axis by default),
  // one untangling after both stages, back to the reconstruction's positions, replaces one
  // after each: the search over the mesh is most of an untangling's cost.
  const bool untangle_once = in.project && in.carve && in.carving.side_passes == 0;
  PointMatrix reconstructed;
  if (in.project) {
    PointMatrix before = result.mesh->vertices;
    ContactProjectionOptions projection = in.projection;
    projection.progress = stages.fraction("projection");
    result.projection =
        stages.run("projection", "projecting the mesh onto the contact points", [&] {
          return project_to_contact_points(*result.mesh, cp.points, cp.normals, in.contact_depths,
                                           result.band_spacing, projection);
        });
    if (untangle_once)
      reconstructed = std::move(before);
    else
      untangle(before, result, stages);
  }
  if (!in.carve) return;
  const PointMatrix before = untangle_once ? std::move(reconstructed) : result.mesh->vertices;
  const Samples& samples = in.carving_samples;
  CarvingOptions carving = in.carving;
  carving.progress = stages.fraction("carving");
  result.carving = stages.run("carving", "carving the mesh out of the samples' spheres", [&] {
    return carve_mesh(*result.mesh, samples.points, samples.values, result.band_spacing, carving);
  });
  untangle(before, result, stages);
  // The untangling can undo the moves that put a sample next to a thin gap on its side.
  if (options.side_repair == Switch::On ||
      (options.side_repair == Switch::Auto && in.carving.side_passes > 0))
    result.side_repair = stages.run("side repair", "denting the mesh off wrong-side samples", [&] {
      return repair_sample_sides(*result.mesh, samples.points, samples.values, result.band_spacing);
    });
}

std::string contact_point_shortage(const GridSource& grid, const ContourOptions& options,
                                   const ContactPoints& cp) {
  if (cp.size() == 0) return kNoContactPoint;
  // An exact distance keeps at least about one contact point per grid cell the surface
  // crosses (flat faces aligned with the grid hide the rest); far fewer means the values are
  // not distances.
  if (options.method == Method::Gcp && grid) {
    const long crossings = grid.sign_change_edges();
    if (10 * long(cp.size()) < crossings)
      return "only " + std::to_string(cp.size()) + " contact points for " +
             std::to_string(crossings) + " grid edges crossing the surface";
  }
  return "";
}

ReconstructionInputs prepare_reconstruction(const BandSamples& band,
                                            const BandOptions& band_options, const GridSource& grid,
                                            const ContourOptions& options, ContourResult& result) {
  const Method method = options.method;
  ReconstructionInputs in;
  in.zero_set_truncation = grid_truncation(band.truncation, band_options.value_scale);
  PoissonOptions& popt = in.poisson;
  popt = options.poisson;
  popt.progress = options.progress;
  popt.progress_fraction = options.progress_fraction;
  popt.cancel = options.cancel;
  in.auto_depth = popt.depth == 0;
  if (popt.depth == 0) popt.depth = auto_poisson_depth(band.samples.points, band.spacing);
  result.poisson_depth = popt.depth;
  if (popt.refine_dilation == 0) popt.refine_dilation = band.samples_per_axis < 256 ? 2 : 1;
  // A grid whose sides are inside in part cuts the surface: its far field is inside there.
  if (grid && grid.sides_inside()) popt.dirichlet_fallback = false;
  // GCP's mesh keeps the samples next to the surface on their sides.
  result.sign_constraints =
      method == Method::Gcp &&
      (options.enforce_signs == Switch::Auto ? auto_sign_constraints(band.samples_per_axis)
                                             : options.enforce_signs == Switch::On);
  if (result.sign_constraints)
    in.sides = samples_near_surface(band, options.sign_band * band.spacing);
  // Projection is on at every resolution with auto (ContourOptions::project). It weighs each
  // contact point by its sample's |value| (the points still name the band's samples here).
  in.project = method == Method::Gcp && options.project != Switch::Off;
  in.projection = options.projection;
  if (in.project) in.contact_depths = contact_depths(*result.contact_points, band.samples.values);
  // Carving needs the band's own samples after the reconstruction (not its margin).
  in.carve = method == Method::Gcp && options.carve != Switch::Off;
  // (Only with the automatic band: a band the user chose bounds every sample used.)
  const double carving_band = auto_carving_band(options.band, band.samples_per_axis);
  if (in.carve && grid && carving_band > band.band) {
    BandOptions wide = band_options;
    wide.band = carving_band;
    wide.margin = 0;
    in.carving_samples = core_samples(grid.select_band(wide));
  } else if (in.carve) {
    in.carving_samples = core_samples(band);
  }
  in.carving = options.carving;
  if (options.carve_sides == Switch::Off ||
      (options.carve_sides == Switch::Auto && !auto_carve_sides(band.samples_per_axis)))
    in.carving.side_passes = 0;
  return in;
}

void reconstruct_mesh(ReconstructionInputs inputs, const GridSource& grid,
                      const ContourOptions& options, ContourResult& result, Stages& stages) {
  poisson_stage(inputs, options, result, stages);
  // The iso-surface closes tiny bubbles where chi grazes the iso-value next to the surface
  // (~100 of extent < 0.5 h on the shared meshes at 32^3): no piece that small comes from
  // samples a spacing apart.
  result.pieces_removed = remove_small_pieces(*result.mesh, result.band_spacing);
  // Cut before projection and carving, which would work on the outer part for nothing, and
  // again after them, as they move the cut's vertices a little.
  clip_to_grid(grid, options, result);
  if (!result.fallback.empty()) return;
  refine_stage(inputs, options, result, stages);
  if (options.zero_set == Switch::On && grid.dense) {
    // Values that are no exact distances: the whole mesh onto the grid's zero set, as the local
    // reconstruction's bricks put theirs. Poisson's surface of their contact points lies 2.6x /
    // 10x marching cubes' L1 from a neural SDF's zero set on its 64^3 / 128^3 grid, parts of it
    // more than a spacing off: moves of up to 2 spacings (0.5: 0.19x / 3.4x MC's; 1: 0.15x /
    // 1.5x; 2: 0.15x / 0.33x), each undone where it makes the mesh cross itself.
    const PointMatrix before = result.mesh->vertices;
    const std::vector<char> all(std::size_t(before.rows()), 1);
    stages.run("zero set", "moving the mesh onto the grid's zero set", [&] {
      ZeroSetRefinementOptions o;
      o.max_move = 2;
      o.truncation = inputs.zero_set_truncation;  // as the local reconstruction's bricks refuse
      return refine_on_zero_set(result.mesh->vertices, all, *grid.dense, o);
    });
    untangle(before, result, stages);
  }
  if (result.clipped_to_grid) clip_to_grid(grid, options, result);
  if (result.fallback.empty() && options.method == Method::Gcp && grid)
    check_on_zero_set(grid, result);
}

}  // namespace sdfcontour::detail
