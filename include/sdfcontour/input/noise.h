// Noisy fields: how noisy a grid's values are near the surface, and a Gaussian smoothing that
// brings them back to something GCP (or marching cubes) can contour in one piece.
#pragma once

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// A robust estimate of the standard deviation of white noise on the values near the surface
/// (|value| < 3 spacings), in the values' units: 1.4826 * median |fourth difference| / sqrt(70)
/// over the three axes. A smooth field's fourth differences are ~h^4 times its fourth derivative
/// (small next to noise even on coarse grids; kinks at the medial axis are outliers the median
/// ignores); noise of deviation s measures s. Stencils touching a truncated value are left out.
/// NaN for fewer than 16 such points or a grid under 5 samples on an axis.
double noise_level(const GridView& grid, const Truncation& truncation = {});

/// The grid convolved with a Gaussian of `sigma` samples (the same on each axis), truncated at
/// 3 sigma, the edge values repeated beyond the grid. A distance to a surface of radius r moves
/// by ~(sigma h)^2 / r; white noise shrinks ~(2 sqrt(pi) sigma)^(3/2) times (6.7 for sigma 1).
Grid gaussian_smoothed(const GridView& grid, double sigma);

}  // namespace sdfcontour
