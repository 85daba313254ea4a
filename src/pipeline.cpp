#include "sdfcontour/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "enum_names.h"
#include "sdfcontour/bricks.h"
#include "sdfcontour/field_agreement.h"
#include "sdfcontour/marching.h"
#include "sdfcontour/mesh_properties.h"
#include "sdfcontour/mesh_transform.h"

namespace sdfcontour {

namespace {
const detail::NameTable<Method> kMethods = {{"gcp", Method::Gcp},
                                            {"gtcp", Method::Gtcp},
                                            {"mc", Method::Mc},
                                            {"mt-rt", Method::MtRt},
                                            {"mt-dt", Method::MtDt}};
const detail::NameTable<GradientSource> kGradientSources = {{"regular", GradientSource::Regular},
                                                            {"delaunay", GradientSource::Delaunay},
                                                            {"knn", GradientSource::Knn}};
const detail::NameTable<Switch> kSwitches = {
    {"auto", Switch::Auto}, {"on", Switch::On}, {"off", Switch::Off}};
}  // namespace

Switch parse_switch(const std::string& what, const std::string& name) {
  return detail::parse_name(kSwitches, what, name);
}

Method parse_method(const std::string& name) {
  return detail::parse_name(kMethods, "method", name);
}
std::string method_name(Method method) {
  return detail::name_of(kMethods, method);
}
GradientSource parse_gradient_source(const std::string& name) {
  return detail::parse_name(kGradientSources, "gradient source", name);
}
std::string gradient_source_name(GradientSource source) {
  return detail::name_of(kGradientSources, source);
}

int auto_poisson_depth(const PointMatrix& points, double spacing) {
  if (points.rows() == 0 || !(spacing > 0)) return 8;
  const double extent = (points.colwise().maxCoeff() - points.colwise().minCoeff()).maxCoeff();
  const double samples_per_axis = extent / spacing + 1;
  return samples_per_axis > 513 ? 11 : samples_per_axis > 257 ? 10 : samples_per_axis > 129 ? 9 : 8;
}

bool auto_sign_constraints(double samples_per_axis) {
  return samples_per_axis < 128;
}

namespace {

// Times each stage and reports its start through the progress callback.
class Stages {
 public:
  Stages(ContourResult& result, const ContourOptions& options)
      : result_(result), options_(options) {}
  template <class F>
  auto run(const std::string& name, const std::string& message, F&& work) {
    check_cancel(options_.cancel);
    if (options_.progress) options_.progress(message);
    const auto start = std::chrono::steady_clock::now();
    auto finish = [&] {
      result_.stages.push_back(
          {name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
    };
    if constexpr (std::is_void_v<decltype(work())>) {
      work();
      finish();
    } else {
      auto value = work();
      finish();
      return value;
    }
  }

 private:
  ContourResult& result_;
  const ContourOptions& options_;
};

}  // namespace

namespace {

// On exact distances (51 grids: the shared meshes at 16^3, 32^3, 64^3) no vertex is that far off;
// on a torus implicit (x^2+y^2+z^2+R^2-r^2)^2 - 4R^2(x^2+y^2) at 64^3, 28% are.
constexpr double kMostOffZeroSet = 0.01;
// Noise above this many spacings is smoothed away before GCP (ContourOptions::smooth_noise).
// Exact distances to the shared meshes measure at most 0.067 (armadillo 16^3), 0.045 at 32^3.
constexpr double kNoisy = 0.08;

// GCP's mesh cannot be trusted on these values (they do not behave as distances).
class NotDistances : public Error {
 public:
  using Error::Error;
};

// GCP's mesh must lie on the field's zero set: more than 1% of its vertices a spacing or more
// off it means the contact points were not on the surface (a smooth implicit whose gradient norm
// varies along the surface passes the other checks, then makes a mesh of ~2000 pieces).
void check_on_zero_set(const GridView& grid, ContourResult& result) {
  const double h = grid.spacing().maxCoeff();
  result.off_zero_set = fraction_off_zero_set(grid, *result.mesh, h, result.value_scale);
  if (result.off_zero_set > kMostOffZeroSet) {
    std::ostringstream message;
    message << std::setprecision(3) << 100 * result.off_zero_set
            << "% of the mesh's vertices lie more than a spacing off the field's zero set";
    throw NotDistances(message.str());
  }
  // Nor more pieces than marching cubes finds in the same field: the extra ones are bubbles
  // around contact points that strayed (noise of 0.5 h, smoothed, left 6 on a torus).
  // Marching cubes finds at least one piece in a field with a sign change, so it runs (on the
  // whole grid) only when GCP's mesh has more.
  const int pieces = connected_components(*result.mesh);
  if (pieces <= 1) return;
  const int mc_pieces = connected_components(marching_cubes(grid));
  if (pieces > mc_pieces)
    throw NotDistances("the mesh has " + std::to_string(pieces) +
                       " connected pieces where marching cubes finds " + std::to_string(mc_pieces));
}

// Whether some sample on the grid's sides is inside (negative): the surface runs out of the grid
// (or the grid lies inside it), so the far field is not all outside.
bool grid_sides_inside(const GridView& grid) {
  const auto& n = grid.dims;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j) {
      const bool side_ij = i == 0 || j == 0 || i == n[0] - 1 || j == n[1] - 1;
      for (int k = 0; k < n[2]; k += side_ij ? 1 : n[2] - 1) {
        if (grid.value(grid.index(i, j, k)) < 0) return true;
        if (n[2] == 1) break;
      }
    }
  return false;
}

// What contour() measures of a grid before choosing to smooth it, handed on so that the
// pipeline does not measure it again.
struct GridMeasures {
  GradientNormSummary gradient_norms;  // with the truncation of the options' band
  double noise = 0;                    // in spacings, see noise_in_spacings
};

// The grid validated, its gradient norms, and the noise on its values near the surface, in
// spacings. A distance scaled by m has its noise scaled by m too, so the noise is divided by the
// gradient norm when that is far from 1 (by more than half: noise itself inflates the measured
// norm, 1.25 at 0.5 h).
GridMeasures measure_grid(const GridView& grid, const ContourOptions& options) {
  validate_grid(grid);
  const Truncation truncation = resolve_truncation(grid, options.band);
  GridMeasures m;
  m.gradient_norms = gradient_norm_summary(grid, truncation);
  const double slope = m.gradient_norms.median;
  const double scale = std::isfinite(slope) && slope > 0 && std::abs(slope - 1) > 0.5 ? slope : 1;
  m.noise = noise_level(grid, truncation) / scale / grid.spacing().maxCoeff();
  return m;
}

// Below 128 samples per axis a grid's mesh is carved by every sample within this many spacings,
// not only the band's 8: the farther balls are large (64^3: wingnut and hammer 6-7% lower L1,
// bunny 1%; every sample gains little more; docs/carving.md). Finer grids gain less for more.
constexpr double kCarvingBand = 16;

// The band's samples proper, without the margin that only closes their stars.
Samples core_samples(const BandSamples& band) {
  const Samples& s = band.samples;
  const Eigen::Index n = Eigen::Index(std::count(band.core.begin(), band.core.end(), 1));
  Samples out;
  out.points.resize(n, 3);
  out.values.resize(n);
  for (Eigen::Index i = 0, q = 0; i < s.values.size(); ++i)
    if (band.core[std::size_t(i)]) {
      out.points.row(q) = s.points.row(i);
      out.values[q++] = s.values[i];
    }
  return out;
}

// `measured`: the grid's measures when contour() took them (the grid is then validated).
ContourResult contour_or_throw(const SdfInput& input, const AnalyticShape* shape,
                               const ContourOptions& options, const GridMeasures* measured) {
  const GridView* grid = grid_view_of(input);
  const ScatteredInput* scattered = std::get_if<ScatteredInput>(&input);
  if (grid) {
    if (!measured) validate_grid(*grid);
    require_sign_change(*grid);
  } else {
    validate_samples(scattered->samples);
    require_sign_change(scattered->samples.values);
  }
  const Method method = options.method;
  if (method == Method::Mc && !grid)
    throw Error("method mc needs a grid input, not scattered samples");
  if (method == Method::Gtcp && !shape)
    throw Error("method gtcp needs the exact SDF, which only built-in shapes provide");
  ContourResult result;
  result.samples = int(grid ? grid->size() : std::size_t(scattered->samples.points.rows()));
  Stages stages(result, options);

  if (method == Method::Mc && options.want_mesh)
    result.mesh =
        stages.run("marching", "marching cubes on " + std::to_string(result.samples) + " samples",
                   [&] { return marching_cubes(*grid); });
  if (!options.want_points && method == Method::Mc) return result;

  BandOptions band_options = options.band;
  if (grid && options.normalize_values && method != Method::Mc && method != Method::Gtcp) {
    result.gradient_norms =
        measured ? measured->gradient_norms
                 : gradient_norm_summary(*grid, resolve_truncation(*grid, band_options));
    result.gradient_norm = result.gradient_norms.median;
    const double m = result.gradient_norm;
    if (std::isfinite(m) && m > 0 && std::abs(m - 1) > 0.1) {
      result.value_scale = band_options.value_scale = 1 / m;
      if (options.progress)
        options.progress("the values change by " + std::to_string(m) +
                         " per unit length near the surface, not 1: rescaled to distances");
    }
  }
  // The other stages see the band's samples as scattered samples; a grid's positions are made
  // for the band only. A band that cannot be used means the values are not distances.
  BandSamples band = stages.run("band", "samples within the band", [&] {
    try {
      return grid ? select_band(*grid, band_options)
                  : select_band(scattered->samples, band_options, scattered->spacing);
    } catch (const Cancelled&) {
      throw;
    } catch (const InternalError&) {
      throw;
    } catch (const Error& e) {
      // No usable band in a truncated grid: values clamped too close to the surface to be
      // distances (a band the user narrowed stays the user's error).
      if (grid && resolve_truncation(*grid, band_options).detected()) throw NotDistances(e.what());
      throw;
    }
  });
  result.band_samples = int(band.samples.values.size());
  result.band_spacing = band.spacing;
  result.band_spacings = band.band;
  result.truncation = band.truncation;
  const Samples& s = band.samples;
  const std::string n = std::to_string(result.band_samples);

  // Only the band proper gives contact points; its margin closes their stars.
  const std::vector<char>* core = &band.core;
  const std::string n_core = std::to_string(std::count(band.core.begin(), band.core.end(), 1));
  const bool contact_mesh = (method == Method::Gcp || method == Method::Gtcp) && options.want_mesh;
  if (method == Method::Gtcp && (options.want_points || options.want_mesh))
    result.contact_points =
        stages.run("contact_points", "exact contact points of " + n_core + " samples",
                   [&] { return exact_contact_points(s.points, *shape, core); });

  // --points with any method but gtcp gives GCP contact points.
  const bool need_gcp = (options.want_points && method != Method::Gtcp) ||
                        (method == Method::Gcp && options.want_mesh);
  // GCP from the regular triangulation runs brick by brick (the same points, less memory).
  // Bricks need a band (or a truncation): without one, the weights are unbounded and no halo
  // is local.
  const double largest = s.values.size() ? s.values.cwiseAbs().maxCoeff() : 0.0;
  const bool bounded = std::isfinite(options.band.band) || (std::isfinite(band.truncation.inside) &&
                                                            std::isfinite(band.truncation.outside));
  const bool gcp_in_bricks = need_gcp && options.gradient_source == GradientSource::Regular &&
                             options.bricks.size != 0 && bounded;
  BrickOptions bricks = options.bricks;
  if (bricks.halo == 0) bricks.halo = auto_brick_halo(largest, band.spacing);
  bricks.cancel = options.cancel;
  const bool need_regular =
      (need_gcp && !gcp_in_bricks) || (method == Method::MtRt && options.want_mesh);
  const bool need_delaunay = (method == Method::MtDt && options.want_mesh) ||
                             (need_gcp && options.gradient_source == GradientSource::Delaunay);
  TriangulationOptions topt;
  topt.parallel = options.parallel;
  std::optional<Triangulation> regular, delaunay;
  if (need_regular) {
    topt.kind = TriangulationKind::Regular;
    regular = stages.run("triangulation", "regular triangulation of " + n + " samples",
                         [&] { return triangulate(s.points, s.values, topt); });
    result.hidden = regular->hidden_count;
  }
  if (need_delaunay) {
    topt.kind = TriangulationKind::Delaunay;
    delaunay = stages.run("delaunay_triangulation", "Delaunay triangulation of " + n + " samples",
                          [&] { return triangulate(s.points, s.values, topt); });
  }
  if (gcp_in_bricks) {
    result.contact_points =
        stages.run("contact_points", "triangulation, gradients and contact points in bricks", [&] {
          std::function<void(int, int)> report = [&](int done, int total) {
            check_cancel(options.cancel);
            if (options.progress_fraction) options.progress_fraction("bricks", done, total);
          };
          BrickStats st;
          ContactPoints cp = brick_contact_points(s, band.spacing, options.gradient,
                                                  options.contact, bricks, &st, report, core);
          result.bricks = st;
          return cp;
        });
    result.hidden = result.contact_points->hidden;
  } else if (need_gcp) {
    const PointMatrix gradients = stages.run("gradients", "gradients at " + n + " samples", [&] {
      switch (options.gradient_source) {
        case GradientSource::Knn:
          return knn_gradients(s.points, s.values, options.knn);
        case GradientSource::Delaunay:
          return vertex_gradients(s.points, s.values, *delaunay, options.gradient);
        case GradientSource::Regular:
          break;
      }
      return vertex_gradients(s.points, s.values, *regular, options.gradient);
    });
    result.contact_points = stages.run("contact_points", "contact points and filter", [&] {
      return gradient_contact_points(s.points, s.values, gradients, *regular, options.contact,
                                     core);
    });
  }
  // Projection needs the contact points after the reconstruction, and their depths (|value| of
  // their samples). Auto is on at every resolution (ContourOptions::project).
  const bool project = method == Method::Gcp && contact_mesh && options.project != Switch::Off;
  Eigen::VectorXd contact_depths;
  if (project) {
    const std::vector<int>& from = result.contact_points->samples;
    contact_depths.resize(Eigen::Index(from.size()));
    for (std::size_t q = 0; q < from.size(); ++q)
      contact_depths[Eigen::Index(q)] = std::abs(s.values[from[q]]);
  }
  // Contact points name their samples by input index.
  if (result.contact_points)
    for (int& i : result.contact_points->samples) i = int(band.source[std::size_t(i)]);
  if (contact_mesh) {
    const ContactPoints& cp = *result.contact_points;
    if (cp.size() == 0)
      throw NotDistances(
          "no contact point was kept, so there is nothing to reconstruct a surface from");
    // An exact distance keeps at least about one contact point per grid cell the surface
    // crosses (flat faces aligned with the grid hide the rest); far fewer means the values are
    // not distances.
    if (method == Method::Gcp && grid) {
      const long crossings = sign_change_edges(*grid);
      if (10 * long(cp.size()) < crossings)
        throw NotDistances("only " + std::to_string(cp.size()) + " contact points for " +
                           std::to_string(crossings) + " grid edges crossing the surface");
    }
    PoissonOptions popt = options.poisson;
    popt.progress = options.progress;
    popt.cancel = options.cancel;
    if (popt.depth == 0) popt.depth = auto_poisson_depth(s.points, band.spacing);
    result.poisson_depth = popt.depth;
    if (popt.refine_dilation == 0) popt.refine_dilation = band.samples_per_axis < 256 ? 2 : 1;
    // A grid whose sides are inside in part cuts the surface: its far field is inside there.
    if (grid && grid_sides_inside(*grid)) popt.dirichlet_fallback = false;
    // GCP's mesh keeps the samples next to the surface on their sides.
    SignedSamples sides;
    result.sign_constraints =
        method == Method::Gcp &&
        (options.enforce_signs == Switch::Auto ? auto_sign_constraints(band.samples_per_axis)
                                               : options.enforce_signs == Switch::On);
    if (result.sign_constraints) {
      const double reach = options.sign_band * band.spacing;
      std::vector<Eigen::Index> near;
      for (Eigen::Index i = 0; i < s.values.size(); ++i)
        if (band.core[std::size_t(i)] && std::abs(s.values[i]) <= reach) near.push_back(i);
      sides.points.resize(Eigen::Index(near.size()), 3);
      sides.values.resize(Eigen::Index(near.size()));
      for (std::size_t q = 0; q < near.size(); ++q) {
        sides.points.row(Eigen::Index(q)) = s.points.row(near[q]);
        sides.values[Eigen::Index(q)] = s.values[near[q]];
      }
    }
    // Carving needs the band's own samples after the reconstruction (not its margin).
    const bool carve = method == Method::Gcp && options.carve != Switch::Off;
    Samples carving_samples;
    // (Only with the automatic band: a band the user chose bounds every sample used.)
    if (carve && grid && options.band.band == 0 && band.band < kCarvingBand &&
        band.samples_per_axis < 128) {
      BandOptions wide = band_options;
      wide.band = kCarvingBand;
      wide.margin = 0;
      carving_samples = core_samples(select_band(*grid, wide));
    } else if (carve) {
      carving_samples = core_samples(band);
    }
    CarvingOptions carving = options.carving;
    if (options.carve_sides == Switch::Off ||
        (options.carve_sides == Switch::Auto && grid && band.samples_per_axis >= 128))
      carving.side_passes = 0;
    // Nothing else after the reconstruction needs the samples or triangulations: free them first.
    band = BandSamples();
    regular.reset();
    delaunay.reset();
    release_resident_pages(input);
    // The points and normals go to the reconstruction rather than a copy of them (at 512^3,
    // 180 MB): freed there once mapped into its own copy unless asked for, else given back.
    ContactPoints& lent = *result.contact_points;
    OrientedPoints oriented{std::move(lent.points), std::move(lent.normals), {}};
    PoissonResult p = stages.run(
        "poisson", "screened Poisson reconstruction of " + std::to_string(cp.size()) + " points",
        [&] {
          SignConstraintOptions sopt = options.sign_constraints;
          sopt.radius = options.sign_radius * result.band_spacing;
          if (!options.want_points && !project)
            return poisson_reconstruct(std::move(oriented), popt, sides, sopt);
          return poisson_reconstruct(oriented, popt, sides, sopt);
        });
    lent.points = std::move(oriented.points);
    lent.normals = std::move(oriented.normals);
    result.mesh = std::move(p.mesh);
    result.sign_violations = p.sign_violations;
    result.sign_violations_left = p.sign_violations_left;
    result.sign_constraints_dropped = p.sign_constraints_dropped;
    for (const auto& [name, seconds] : p.seconds) result.poisson_stages.push_back({name, seconds});
    // The iso-surface closes tiny bubbles where chi grazes the iso-value next to the surface
    // (~100 of extent < 0.5 h on the shared meshes at 32^3): no piece that small comes from
    // samples a spacing apart.
    result.pieces_removed = remove_small_pieces(*result.mesh, result.band_spacing);
    // A surface that runs out of the grid (a cropped scan's TSDF) ends at its sides, as
    // marching cubes' does; the reconstruction closed it outside, where no sample was. Cut
    // before projection and carving, which would work on that part for nothing, and again
    // after them, as they move the cut's vertices a little.
    auto clip_to_grid = [&] {
      if (method != Method::Gcp || !grid) return;
      result.clipped_to_grid |= clip_mesh_to_box(*result.mesh, grid->bounds.min, grid->bounds.max);
      if (result.mesh->triangles.rows() == 0)
        throw NotDistances("no part of the reconstructed surface lies in the grid");
    };
    clip_to_grid();
    // Projection and carving move vertices by a fraction of a spacing, which can push a thin
    // part's sheet through the other; such moves are undone, the reconstruction's own mesh
    // being free of crossings.
    auto untangle = [&](const PointMatrix& before) {
      const UntangleStats u = stages.run("untangling", "undoing moves that cross the mesh", [&] {
        return revert_self_intersections(*result.mesh, before);
      });
      UntangleStats& sum = result.untangling.emplace(result.untangling.value_or(UntangleStats{}));
      sum.rounds += u.rounds;
      sum.vertices_reverted += u.vertices_reverted;
      sum.intersections_found += u.intersections_found;
      sum.intersections_left += u.intersections_left;
    };
    // Where carving moves vertices only (no side passes, from 128 samples per axis by default),
    // one untangling after both stages, back to the reconstruction's positions, replaces one
    // after each: the search over the mesh is most of an untangling's cost.
    const bool untangle_once = project && carve && carving.side_passes == 0;
    PointMatrix reconstructed;
    if (project) {
      PointMatrix before = result.mesh->vertices;
      result.projection =
          stages.run("projection", "projecting the mesh onto the contact points", [&] {
            return project_to_contact_points(*result.mesh, lent.points, lent.normals,
                                             contact_depths, result.band_spacing,
                                             options.projection);
          });
      if (untangle_once)
        reconstructed = std::move(before);
      else
        untangle(before);
    }
    if (carve) {
      const PointMatrix before = untangle_once ? std::move(reconstructed) : result.mesh->vertices;
      result.carving = stages.run("carving", "carving the mesh out of the samples' spheres", [&] {
        return carve_mesh(*result.mesh, carving_samples.points, carving_samples.values,
                          result.band_spacing, carving);
      });
      untangle(before);
      // The untangling can undo the moves that put a sample next to a thin gap on its side.
      if (options.side_repair == Switch::On ||
          (options.side_repair == Switch::Auto && carving.side_passes > 0))
        result.side_repair =
            stages.run("side repair", "denting the mesh off wrong-side samples", [&] {
              return repair_sample_sides(*result.mesh, carving_samples.points,
                                         carving_samples.values, result.band_spacing);
            });
    }
    if (result.clipped_to_grid) clip_to_grid();
    if (method == Method::Gcp && grid) check_on_zero_set(*grid, result);
  }
  if (method == Method::MtRt && options.want_mesh)
    result.mesh = stages.run(
        "marching", "marching tetrahedra on " + std::to_string(regular->tets.rows()) + " tets",
        [&] { return marching_tetrahedra(s.points, s.values, regular->tets); });
  if (method == Method::MtDt && options.want_mesh)
    result.mesh = stages.run(
        "marching", "marching tetrahedra on " + std::to_string(delaunay->tets.rows()) + " tets",
        [&] { return marching_tetrahedra(s.points, s.values, delaunay->tets); });
  return result;
}

}  // namespace

namespace {

// contour_or_throw, or marching cubes' mesh when GCP's cannot be trusted.
ContourResult contour_with_fallback(const SdfInput& input, const AnalyticShape* shape,
                                    const ContourOptions& options,
                                    const GridMeasures* measured = nullptr) {
  try {
    return contour_or_throw(input, shape, options, measured);
  } catch (const NotDistances& e) {
    const GridView* grid = grid_view_of(input);
    if (!grid || options.method != Method::Gcp || !options.want_mesh || options.want_points ||
        !options.fallback_to_mc)
      throw Error(e.what());
    ContourResult result;
    result.samples = int(grid->size());
    result.fallback = std::string(e.what()) + ": the values do not behave as distances";
    if (options.progress)
      options.progress("GCP: " + result.fallback + "; this is marching cubes' mesh instead");
    Stages stages(result, options);
    result.mesh =
        stages.run("marching", "marching cubes on " + std::to_string(result.samples) + " samples",
                   [&] { return marching_cubes(*grid); });
    return result;
  }
}

}  // namespace

ContourResult contour(const SdfInput& input, const AnalyticShape* shape,
                      const ContourOptions& options) {
  const GridView* grid = grid_view_of(input);
  if (!grid || options.method != Method::Gcp || !options.smooth_noise)
    return contour_with_fallback(input, shape, options);
  const GridMeasures measured = measure_grid(*grid, options);
  if (!(measured.noise > kNoisy)) {
    ContourResult result = contour_with_fallback(input, shape, options, &measured);
    result.noise_level = measured.noise;
    return result;
  }
  if (options.progress) {
    std::ostringstream message;
    message << std::setprecision(2) << "the values are noisy (about " << measured.noise
            << " spacings): smoothed with a Gaussian of one sample";
    options.progress(message.str());
  }
  // Smoothed values are no longer distances: their spheres are not empty.
  ContourOptions smoothed = options;
  if (smoothed.carve == Switch::Auto) smoothed.carve = Switch::Off;
  ContourResult result =
      contour_with_fallback(grid_input(gaussian_smoothed(*grid, 1.0)), shape, smoothed);
  result.noise_level = measured.noise;
  result.smoothed = true;
  return result;
}

}  // namespace sdfcontour
