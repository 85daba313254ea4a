// What contour() measures of a grid before anything is built, and the choices it makes from
// that, once (noise, slope, truncation): no later stage runs the pipeline again.
#pragma once

#include "sdfcontour/band/band.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::detail {

// Noise above this many spacings is smoothed away before GCP (ContourOptions::smooth_noise).
// Exact distances to the shared meshes measure at most 0.067 (armadillo 16^3), 0.045 at 32^3.
inline constexpr double kNoisy = 0.08;

// Values clamped this close to the surface (in spacings, on both sides) leave no sample whose
// neighbours are unclamped, so none keeps a contact point: a sphere at 40^3 clamped at 1 spacing
// keeps none, at 1.1 spacings 384, at 1.5 1,760, at 3 6,928. (A hair over one: the clamp's own
// rounding.) Marching cubes' mesh is then the best the values give: at 0.5 and 1 spacing its
// vertices lie 0.020 h and 0.0039 h from the sphere on average, the local reconstruction's on the
// grid's zero set 0.037 h and 0.0032 h.
inline constexpr double kClampedTooClose = 1.05;

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
GridMeasures measure_grid(const GridView& grid, const ContourOptions& options);

// Whether the measured truncation leaves the grid no contact point (kClampedTooClose).
bool clamped_too_close(const GridMeasures& measured, double spacing);

// Where the values are no exact distances, the automatic choices that assume them change
// (ContourOptions::detect_approximate); true if they did.
bool choose_for_approximate_distances(const GridMeasures& measured, ContourOptions& options);

}  // namespace sdfcontour::detail
