#include "sdfcontour/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "pipeline/enum_names.h"
#include "pipeline/pipeline_stages.h"
#include "sdfcontour/extraction/brick_marching.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour {

namespace {
const detail::NameTable<Method> kMethods = {{"gcp", Method::Gcp},
                                            {"gtcp", Method::Gtcp},
                                            {"mc", Method::Mc},
                                            {"mt-rt", Method::MtRt},
                                            {"mt-dt", Method::MtDt}};
const detail::NameTable<GradientSource> kGradientSources = {{"regular", GradientSource::Regular},
                                                            {"delaunay", GradientSource::Delaunay},
                                                            {"knn", GradientSource::Knn},
                                                            {"lattice", GradientSource::Lattice}};
const detail::NameTable<Reconstruction> kReconstructions = {{"auto", Reconstruction::Auto},
                                                            {"poisson", Reconstruction::Poisson},
                                                            {"local", Reconstruction::Local}};
const detail::NameTable<Switch> kSwitches = {
    {"auto", Switch::Auto}, {"on", Switch::On}, {"off", Switch::Off}};
}  // namespace

Switch parse_switch(const std::string& what, const std::string& name) {
  return detail::parse_name(kSwitches, what, name);
}

Reconstruction parse_reconstruction(const std::string& name) {
  return detail::parse_name(kReconstructions, "reconstruction", name);
}
std::string reconstruction_name(Reconstruction reconstruction) {
  return detail::name_of(kReconstructions, reconstruction);
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

namespace {

using detail::Stages;

// Noise above this many spacings is smoothed away before GCP (ContourOptions::smooth_noise).
// Exact distances to the shared meshes measure at most 0.067 (armadillo 16^3), 0.045 at 32^3.
constexpr double kNoisy = 0.08;

// What contour() measures of a grid before choosing to smooth it, handed on so that the
// pipeline does not measure it again.
struct GridMeasures {
  Truncation truncation;               // the options' band's, found in the grid once
  GradientNormSummary gradient_norms;  // with that truncation
  double noise = 0;                    // in spacings, see noise_in_spacings
};

// The grid validated, its gradient norms, and the noise on its values near the surface, in
// spacings. A distance scaled by m has its noise scaled by m too, so the noise is divided by the
// gradient norm when that is far from 1 (by more than half: noise itself inflates the measured
// norm, 1.25 at 0.5 h).
GridMeasures measure_grid(const GridView& grid, const ContourOptions& options) {
  validate_grid(grid);
  GridMeasures m;
  const Truncation truncation = m.truncation = resolve_truncation(grid, options.band);
  m.gradient_norms = gradient_norm_summary(grid, truncation);
  const double slope = m.gradient_norms.median;
  const double scale = std::isfinite(slope) && slope > 0 && std::abs(slope - 1) > 0.5 ? slope : 1;
  m.noise = noise_level(grid, truncation) / scale / grid.spacing().maxCoeff();
  return m;
}

// Values clamped this close to the surface (in spacings, on both sides) leave no sample whose
// neighbours are unclamped, so none keeps a contact point: a sphere at 40^3 clamped at 1 spacing
// keeps none, at 1.1 spacings 384, at 1.5 1,760, at 3 6,928. (A hair over one: the clamp's own
// rounding.) Marching cubes' mesh is then the best the values give: at 0.5 and 1 spacing its
// vertices lie 0.020 h and 0.0039 h from the sphere on average, the local reconstruction's on the
// grid's zero set 0.037 h and 0.0032 h.
constexpr double kClampedTooClose = 1.05;

// Whether the measured truncation leaves the grid no contact point (kClampedTooClose).
bool clamped_too_close(const GridMeasures& measured, double spacing) {
  const Truncation& t = measured.truncation;
  const double slope = measured.gradient_norms.slope > 0 ? measured.gradient_norms.slope : 1.0;
  return t.detected() && std::max(t.inside, t.outside) / slope <= kClampedTooClose * spacing;
}

// Throws Error where the input cannot be contoured with the options' method. `measured`: the
// grid was validated already.
void check_input_for_method(const detail::GridSource& grid, const ScatteredInput* scattered,
                            const AnalyticShape* shape, const ContourOptions& options,
                            const GridMeasures* measured) {
  if (grid.dense) {
    if (!measured) validate_grid(*grid.dense);
    require_sign_change(*grid.dense);
  } else if (grid.sparse) {
    validate_sparse_grid(*grid.sparse);
    require_sign_change(*grid.sparse);
  } else {
    validate_samples(scattered->samples);
    require_sign_change(scattered->samples.values);
  }
  if (options.method == Method::Mc && !grid)
    throw Error("method mc needs a grid input, not scattered samples");
  if (grid.sparse && options.reconstruction == Reconstruction::Local &&
      (options.method == Method::Gcp || options.method == Method::Gtcp) && options.want_mesh)
    throw Error(
        "the local reconstruction of a sparse grid goes brick by brick (its blocks contoured "
        "one by one), not through contour()");
  if (!grid && options.reconstruction == Reconstruction::Local &&
      (options.method == Method::Gcp || options.method == Method::Gtcp))
    throw Error(
        "the local reconstruction needs a grid input (scattered samples and .vdb level "
        "sets: --reconstruction poisson)");
  if (options.method == Method::Gtcp && !shape)
    throw Error(
        "method gtcp needs the exact SDF, which only built-in shapes provide "
        "(contour_with_exact_sdf)");
}

// Values that change by m per unit length near the surface (m far from 1) are rescaled by 1/m
// into distances: result.value_scale and the band's value_scale.
void rescale_to_distances(const GridView& grid, const ContourOptions& options,
                          const GridMeasures* measured, BandOptions& band_options,
                          ContourResult& result) {
  result.gradient_norms = measured
                              ? measured->gradient_norms
                              : gradient_norm_summary(grid, resolve_truncation(grid, band_options));
  result.gradient_norm = result.gradient_norms.median;
  const double m = result.gradient_norms.slope;
  if (distance_value_scale(m) != 1.0) {
    result.value_scale = band_options.value_scale = distance_value_scale(m);
    if (options.progress)
      options.progress("the values change by " + std::to_string(m) +
                       " per unit length near the surface, not 1: rescaled to distances");
  }
}

// The band's samples, seen by the later stages as scattered samples (a grid's positions are made
// for the band only). A band that cannot be used means the values are not distances
// (result.fallback says why).
BandSamples band_stage(const detail::GridSource& grid, const ScatteredInput* scattered,
                       const BandOptions& band_options, ContourResult& result, Stages& stages) {
  return stages.run("band", "samples within the band", [&] {
    try {
      return grid ? grid.select_band(band_options)
                  : select_band(scattered->samples, band_options, scattered->spacing);
    } catch (const Cancelled&) {
      throw;
    } catch (const InternalError&) {
      throw;
    } catch (const Error& e) {
      // No usable band in a truncated grid: values clamped too close to the surface to be
      // distances (a band the user narrowed stays the user's error).
      if (!grid.dense || !resolve_truncation(*grid.dense, band_options).detected()) throw;
      result.fallback = e.what();
      return BandSamples();
    }
  });
}

// A grid read a block at a time (a .vdb level set): marching cubes or GCP's local reconstruction
// brick by brick, the values taken as distances (a level set's are), nothing measured of the
// whole grid; its own truncation (the background) unless the options give one.
ContourResult contour_blocked_grid(const BlockedGridInput& input, const ContourOptions& given) {
  const BlockedGrid& grid = input.grid;
  validate_grid_geometry(grid);
  ContourOptions options = given;
  if (options.band.truncation_mode == TruncationMode::Auto && input.truncation > 0) {
    options.band.truncation_mode = TruncationMode::Given;
    options.band.truncation = input.truncation;
  }
  const bool mc = options.method == Method::Mc && !options.want_points;
  if (!options.want_mesh ||
      (!mc && (options.method != Method::Gcp || options.reconstruction == Reconstruction::Poisson ||
               !local_gradients(options.gradient_source) || !std::isfinite(options.band.band))))
    throw Error(
        "a grid read block by block (a .vdb level set) takes marching cubes or GCP's local "
        "reconstruction to a mesh, with regular or lattice gradients and a finite band: read "
        "it as scattered samples for the rest");
  ContourResult result;
  const double samples = double(grid.dims[0]) * grid.dims[1] * grid.dims[2];
  result.samples = int(std::min(samples, double(std::numeric_limits<int>::max())));
  Stages stages(result, options);
  if (mc) {
    result.mesh = stages.run("marching", "marching cubes brick by brick",
                             [&] { return marching_cubes(grid, kLocalBrick); });
    if (result.mesh->triangles.rows() == 0)
      throw Error("no surface: the values have no sign change inside the grid");
    return result;
  }
  detail::reconstruct_in_bricks(grid, options.band, options, result, stages);
  return result;
}

// The outputs of a grid contoured in its own frame, placed in the world (a rigid motion: the
// distances, and so the mesh, are the same).
void place_in_world(const Eigen::Affine3d& world_from_grid, ContourResult& result) {
  auto place = [&](PointMatrix& points, bool directions) {
    for (Eigen::Index r = 0; r < points.rows(); ++r) {
      const Eigen::Vector3d p = points.row(r).transpose();
      points.row(r) = (directions ? Eigen::Vector3d(world_from_grid.linear() * p)
                                  : Eigen::Vector3d(world_from_grid * p))
                          .transpose();
    }
  };
  if (result.mesh) place(result.mesh->vertices, false);
  if (result.contact_points) {
    place(result.contact_points->points, false);
    place(result.contact_points->normals, true);
  }
}

// `measured`: the grid's measures when contour() took them (the grid is then validated).
ContourResult contour_or_throw(const SdfInput& input, const AnalyticShape* shape,
                               const ContourOptions& options, const GridMeasures* measured) {
  if (const auto* blocked = std::get_if<BlockedGridInput>(&input)) {
    ContourResult result = contour_blocked_grid(*blocked, options);
    if (blocked->world_from_grid) place_in_world(*blocked->world_from_grid, result);
    return result;
  }
  const detail::GridSource grid = detail::grid_source_of(input);
  const ScatteredInput* scattered = std::get_if<ScatteredInput>(&input);
  check_input_for_method(grid, scattered, shape, options, measured);
  const Method method = options.method;
  ContourResult result;
  result.samples =
      int(grid ? grid.geometry().size() : std::size_t(scattered->samples.points.rows()));
  Stages stages(result, options);

  if (method == Method::Mc && options.want_mesh)
    result.mesh =
        stages.run("marching", "marching cubes on " + std::to_string(result.samples) + " samples",
                   [&] { return grid.marching_cubes(); });
  if (!options.want_points && method == Method::Mc) return result;

  BandOptions band_options = options.band;
  // One truncation detection per grid: every later stage (band, bricks, carving, gradient norms)
  // reads it from here.
  if (grid.dense && band_options.truncation_mode == TruncationMode::Auto) {
    band_options.resolved =
        measured ? measured->truncation : resolve_truncation(*grid.dense, band_options);
    band_options.truncation_mode = TruncationMode::Resolved;
  }
  if (grid.dense && options.normalize_values && method != Method::Mc && method != Method::Gtcp) {
    rescale_to_distances(*grid.dense, options, measured, band_options, result);
    if (band_options.value_scale != 1) {
      // Every later stage reads distances: the values scaled once, in their own precision
      // (a field of 1e-200 would underflow in the squares and quotients of later stages), and
      // their truncation, found or given in the values' units, with them.
      const double scale = band_options.value_scale;
      ContourOptions distances = options;
      distances.normalize_values = false;
      if (band_options.truncation_mode != TruncationMode::None) {
        const Truncation t = resolve_truncation(*grid.dense, band_options);  // (resolved above)
        distances.band.truncation_mode = TruncationMode::Resolved;
        distances.band.resolved.inside = t.inside * scale;
        distances.band.resolved.outside = t.outside * scale;
      }
      ContourResult scaled = contour_or_throw(
          SdfInput(detail::mapped_grid(*grid.dense, [scale](double v) { return v * scale; })),
          shape, distances, nullptr);
      scaled.value_scale = result.value_scale;
      scaled.gradient_norm = result.gradient_norm;
      scaled.gradient_norms = result.gradient_norms;
      scaled.stages.insert(scaled.stages.begin(), result.stages.begin(), result.stages.end());
      return scaled;
    }
  }
  if (const auto* sparse = std::get_if<SparseGridInput>(&input)) {
    // Measured where it was sampled, as rescale_to_distances measures a dense grid.
    result.gradient_norm = sparse->gradient_norm;
    result.value_scale = band_options.value_scale = sparse->value_scale;
  }
  if (detail::bricked_local(grid.dense, options)) {
    // A file-mapped grid is held a block at a time: its pages go once a brick has its block.
    // With want_points the bricks hand on the contact points they made the mesh from.
    detail::reconstruct_in_bricks(*grid.dense, band_options, options, result, stages,
                                  [&] { release_resident_pages(input); });
    return result;
  }
  BandSamples band = band_stage(grid, scattered, band_options, result, stages);
  if (!result.fallback.empty()) return result;
  result.band_samples = int(band.samples.values.size());
  result.isolated_samples = band.isolated;
  if (band.isolated > 0 && options.progress)
    options.progress("dropped " + std::to_string(band.isolated) +
                     " isolated samples (fewer than 3 others nearby)");
  result.band_spacing = band.spacing;
  result.band_spacings = band.band;
  result.truncation = band.truncation;

  detail::SampleTriangulations triangulations =
      detail::contact_point_stage(band, shape, options, result, stages);
  const bool contact_mesh = (method == Method::Gcp || method == Method::Gtcp) && options.want_mesh;
  const bool local = contact_mesh && grid.dense && options.reconstruction == Reconstruction::Local;
  if (contact_mesh) {
    // Poisson's surface needs its points; the local reconstruction's cells decide alone, as in
    // the bricks (local_stage.cpp).
    const std::string few = detail::contact_point_shortage(grid, options, *result.contact_points);
    if (!few.empty() && !local) {
      result.fallback = few;
      return result;
    }
    if (!few.empty() && !options.fallback_to_mc)
      throw Error(few + ": the values do not behave as distances");
    if (!few.empty() && options.progress) options.progress(few + detail::kCellsFromCrossings);
  }
  if (local) {
    const detail::ReconstructionInputs in =
        detail::prepare_reconstruction(band, band_options, grid, options, result);
    detail::reconstruct_locally(*grid.dense, in, options, result, stages);
  }
  std::optional<detail::ReconstructionInputs> inputs;
  if (contact_mesh && !local) {
    inputs = detail::prepare_reconstruction(band, band_options, grid, options, result);
  }
  // Contact points name their samples by input index.
  if (result.contact_points)
    for (int& i : result.contact_points->samples) i = int(band.source[std::size_t(i)]);
  if (contact_mesh && !local) {
    // Nothing after the reconstruction needs the samples or triangulations: free them first.
    band = BandSamples();
    triangulations = {};
    release_resident_pages(input);
    detail::reconstruct_mesh(std::move(*inputs), grid, options, result, stages);
  }
  const Samples& s = band.samples;
  if (method == Method::MtRt && options.want_mesh)
    result.mesh = stages.run(
        "marching",
        "marching tetrahedra on " + std::to_string(triangulations.regular->tets.rows()) + " tets",
        [&] { return marching_tetrahedra(s.points, s.values, triangulations.regular->tets); });
  if (method == Method::MtDt && options.want_mesh)
    result.mesh = stages.run(
        "marching",
        "marching tetrahedra on " + std::to_string(triangulations.delaunay->tets.rows()) + " tets",
        [&] { return marching_tetrahedra(s.points, s.values, triangulations.delaunay->tets); });
  return result;
}

}  // namespace

namespace {

// Marching cubes' mesh where GCP's cannot be had (`why`), or Error(why) where the options want
// GCP's alone (fallback_to_mc off, contact points asked for, no grid). `discarded`: the seconds
// of GCP's work that found it out (0: decided before any).
ContourResult marching_cubes_instead(const SdfInput& input, const ContourOptions& options,
                                     const std::string& why, double discarded) {
  const detail::GridSource grid = detail::grid_source_of(input);
  if (!grid || options.method != Method::Gcp || !options.want_mesh || options.want_points ||
      !options.fallback_to_mc)
    throw Error(why);
  ContourResult result;
  result.samples = int(grid.geometry().size());
  result.fallback = why;
  // The work thrown away is part of the run's cost: said, not hidden.
  if (discarded > 0) result.stages.push_back({"gcp (discarded)", discarded});
  if (options.progress)
    options.progress("GCP: " + result.fallback + "; this is marching cubes' mesh instead");
  Stages stages(result, options);
  result.mesh =
      stages.run("marching", "marching cubes on " + std::to_string(result.samples) + " samples",
                 [&] { return grid.marching_cubes(); });
  return result;
}

// contour_or_throw, or marching cubes' mesh when the Poisson path's mesh shows that the values
// were no distances (off their zero set, more pieces than marching cubes, too few contact points).
ContourResult contour_with_fallback(const SdfInput& input, const AnalyticShape* shape,
                                    const ContourOptions& options,
                                    const GridMeasures* measured = nullptr) {
  const auto started = std::chrono::steady_clock::now();
  ContourResult gcp = contour_or_throw(input, shape, options, measured);
  if (gcp.fallback.empty()) return gcp;
  const double discarded =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return marching_cubes_instead(input, options,
                                gcp.fallback + ": the values do not behave as distances",
                                std::max(discarded, 1e-9));
}

}  // namespace

namespace {

// The mesh merged where the surface is flat enough (AdaptivityOptions), over the contact points
// when the method made them.
void adapt_stage(const SdfInput& input, const ContourOptions& options, ContourResult& result) {
  if (!(options.adaptivity.tolerance > 0) || !result.mesh) return;
  const detail::GridSource grid = detail::grid_source_of(input);
  const double h = result.band_spacing > 0 ? result.band_spacing
                   : grid                  ? grid.geometry().spacing().maxCoeff()
                                           : 0.0;
  if (!(h > 0)) throw Error("adaptivity needs the samples' spacing");
  const bool points = result.contact_points && result.contact_points->points.rows() > 0;
  const PointMatrix none(0, 3);
  Stages stages(result, options);
  AdaptivityStats stats;
  result.mesh = stages.run("adaptivity", "merging the mesh where it is flat", [&] {
    return adapt_mesh(*result.mesh, points ? result.contact_points->points : none,
                      points ? result.contact_points->normals : none, h, options.adaptivity,
                      &stats);
  });
  result.adaptivity = stats;
}

ContourResult contour_before_adaptivity(const SdfInput& input, const AnalyticShape* shape,
                                        const ContourOptions& options);

// Where the values are no exact distances, the automatic choices that assume them change
// (ContourOptions::detect_approximate); true if they did.
bool choose_for_approximate_distances(const GridMeasures& measured, ContourOptions& options) {
  if (!options.detect_approximate || !auto_approximate_distances(measured.gradient_norms))
    return false;
  if (options.reconstruction == Reconstruction::Auto)
    options.reconstruction = Reconstruction::Local;
  if (options.carve == Switch::Auto) options.carve = Switch::Off;
  if (options.zero_set == Switch::Auto) options.zero_set = Switch::On;
  // (Its contact points make false thin parts where the values are no distances.)
  if (options.thin_parts == Switch::Auto) options.thin_parts = Switch::Off;
  if (options.progress) {
    std::ostringstream message;
    message << std::setprecision(2) << "the values are no exact distances (their slope is off 1 by "
            << measured.gradient_norms.smooth_spread
            << " where the field is smooth): the local reconstruction, its vertices on the "
               "grid's tricubic zero set, no carving";
    options.progress(message.str());
  }
  return true;
}

}  // namespace

ContourResult contour(const SdfInput& input, const ContourOptions& options) {
  ContourResult result = contour_before_adaptivity(input, nullptr, options);
  adapt_stage(input, options, result);
  return result;
}

ContourResult contour_with_exact_sdf(const SdfInput& input, const AnalyticShape& shape,
                                     const ContourOptions& options) {
  ContourResult result = contour_before_adaptivity(input, &shape, options);
  adapt_stage(input, options, result);
  return result;
}

namespace {

ContourResult contour_as_measured(const SdfInput& input, const AnalyticShape* shape,
                                  const ContourOptions& options, const GridView* grid,
                                  const GridMeasures& measured);

ContourResult contour_before_adaptivity(const SdfInput& input, const AnalyticShape* shape,
                                        const ContourOptions& options) {
  const GridView* grid = grid_view_of(input);
  if (!grid || options.method != Method::Gcp || !options.smooth_noise)
    return contour_with_fallback(input, shape, options);
  if (options.progress) options.progress("measuring the values near the surface");
  const auto started = std::chrono::steady_clock::now();
  const GridMeasures measured = measure_grid(*grid, options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  ContourResult result = contour_as_measured(input, shape, options, grid, measured);
  // The measuring is the run's time too (passes over the whole grid for the validation, the
  // truncation, the gradient norms and the noise: bunny 256^3, 0.64 s of 6.5 s with edge fans
  // and lattice gradients on a band of 2).
  result.stages.insert(result.stages.begin(), {"measure", seconds});
  return result;
}

// contour_before_adaptivity's choices from the grid's measures.
ContourResult contour_as_measured(const SdfInput& input, const AnalyticShape* shape,
                                  const ContourOptions& options, const GridView* grid,
                                  const GridMeasures& measured) {
  // Decided once, from the grid's measures: no later stage runs the pipeline again.
  if (options.detect_approximate && clamped_too_close(measured, grid->spacing().maxCoeff())) {
    std::ostringstream why;
    why << "the values are clamped within " << kClampedTooClose
        << " spacings of the surface, where no sample keeps a contact point";
    ContourResult result = marching_cubes_instead(input, options, why.str(), 0);
    result.noise_level = measured.noise;
    result.truncation = measured.truncation;
    return result;
  }
  if (!(measured.noise > kNoisy)) {
    ContourOptions chosen = options;
    const bool approximate = choose_for_approximate_distances(measured, chosen);
    ContourResult result = contour_with_fallback(input, shape, chosen, &measured);
    result.noise_level = measured.noise;
    result.approximate_distances = approximate;
    if (!(result.gradient_norm > 0)) {  // a run on the values as given: what was measured
      result.gradient_norms = measured.gradient_norms;
      result.gradient_norm = measured.gradient_norms.median;
    }
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

}  // namespace

}  // namespace sdfcontour
