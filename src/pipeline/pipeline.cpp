#include "sdfcontour/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include "pipeline/grid_measures.h"
#include "pipeline/pipeline_stages.h"
#include "sdfcontour/extraction/brick_marching.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour {

namespace {

using detail::choose_for_approximate_distances;
using detail::clamped_too_close;
using detail::GridMeasures;
using detail::kClampedTooClose;
using detail::kNoisy;
using detail::measure_grid;

using detail::Stages;

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

// `measured`: the grid's measures when contour() took them (the grid is then validated).
ContourResult contour_or_throw(const SdfInput& input, const AnalyticShape* shape,
                               const ContourOptions& options, const GridMeasures* measured) {
  if (const auto* blocked = std::get_if<BlockedGridInput>(&input)) {
    ContourResult result = detail::contour_blocked_grid(*blocked, options);
    if (blocked->world_from_grid) detail::place_in_world(*blocked->world_from_grid, result);
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
    if (local) detail::say_cells_from_crossings(few, options);
  }
  if (local) {
    // The bricks take their points from the whole grid's: the same chain as GCP's own.
    const ContactPoints& cp = *result.contact_points;
    GivenContactPoints given;
    given.points = cp.points;
    given.normals = cp.normals;
    given.depths = contact_depths(cp, band.samples.values);
    for (const int s : cp.samples)
      given.samples.push_back(std::uint64_t(band.source[std::size_t(s)]));
    detail::reconstruct_from_points(*grid.dense, band_options, given, options, result, stages);
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
// of GCP's work that found it out (none: decided before any).
ContourResult marching_cubes_instead(const SdfInput& input, const ContourOptions& options,
                                     const std::string& why, std::optional<double> discarded) {
  const detail::GridSource grid = detail::grid_source_of(input);
  if (!grid || options.method != Method::Gcp || !options.want_mesh || options.want_points ||
      !options.fallback_to_mc)
    throw Error(why);
  ContourResult result;
  result.samples = int(grid.geometry().size());
  result.fallback = why;
  // The work thrown away is part of the run's cost: said, not hidden.
  if (discarded) result.stages.push_back({"gcp (discarded)", *discarded});
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
  return marching_cubes_instead(
      input, options, gcp.fallback + ": the values do not behave as distances", discarded);
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
    ContourResult result = marching_cubes_instead(input, options, why.str(), std::nullopt);
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
