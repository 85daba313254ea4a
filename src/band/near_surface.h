// Internal: one pass over a grid's samples near its surface, for the gradient norms next to its
// sign changes (gradient_norms.cpp), the noise of its values (noise.cpp), or both (measure_grid:
// the grid read once for the two instead of twice).
#pragma once

#include <array>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour::detail {

// One slab's values, its samples in row order.
struct NearSurfaceValues {
  // At the samples next to a sign change: the gradient norms, those without a kink, and those
  // where the field is smooth (CrossingNorms, GradientNormSummary::smooth_spread).
  std::vector<double> all, kinkless, smooth;
  // At the samples with |value| < near: |fourth difference| along each axis (noise_level).
  std::vector<double> d4;
};

struct NearSurfaceRequest {
  bool norms = false;
  bool noise = false;
  double near = 0;
  // The block's samples read, as block indices, each at least 2 from the block's sides.
  std::array<int, 3> from{}, to{};
};

// Per slab i of [from[0], to[0]), in order, the values asked for; stencils that touch a value
// at `truncation` are left out. Empty where a range is.
std::vector<NearSurfaceValues> near_surface_values(const GridView& grid,
                                                   const Truncation& truncation,
                                                   const NearSurfaceRequest& request);

// The median-based noise estimate of noise_level from the slabs' d4 (NaN under 16 values).
double noise_of(const std::vector<NearSurfaceValues>& slabs);

// gradient_norm_summary from the slabs' norms (their smooth ones included).
GradientNormSummary norm_summary_of(const std::vector<NearSurfaceValues>& slabs);

// noise_level's and gradient_norm_summary's slabs of a whole grid, in one pass.
std::vector<NearSurfaceValues> whole_grid_near_surface(const GridView& grid,
                                                       const Truncation& truncation, bool norms,
                                                       bool noise);

}  // namespace sdfcontour::detail
