// The field's gradient norm next to its sign changes: how far the values are from distances.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

#include "band/near_surface.h"
#include "input/parallel_select.h"
#include "input/windowed_passes.h"
#include "sdfcontour/band/band.h"

namespace sdfcontour {

using detail::concatenate;
using detail::near_surface_values;
using detail::NearSurfaceRequest;
using detail::NearSurfaceValues;

namespace {

// The block indices of the samples that crossing_gradient_norms measures: the owned ones at
// least 2 from the whole grid's sides.
NearSurfaceRequest crossing_request(const GridView& grid, std::array<int, 3> own_first,
                                    std::array<int, 3> own_end) {
  const std::array<int, 3> whole = grid.whole_dims();
  NearSurfaceRequest request;
  request.norms = true;
  for (std::size_t a = 0; a < 3; ++a) {
    request.from[a] = std::max(own_first[a], 2) - grid.first[a];
    request.to[a] = std::min(own_end[a], whole[a] - 2) - grid.first[a];
    if (request.from[a] < request.to[a] &&
        (request.from[a] < 2 || request.to[a] + 2 > grid.dims[a]))
      throw Error("the block must hold 2 samples beyond the samples whose gradients it measures");
  }
  return request;
}

double median_of(const std::vector<double>& v) {
  return detail::kth_smallest(v, v.size() / 2);
}

}  // namespace

CrossingNorms crossing_gradient_norms(const GridView& grid, const Truncation& truncation,
                                      std::array<int, 3> own_first, std::array<int, 3> own_end) {
  const std::vector<NearSurfaceValues> slabs =
      near_surface_values(grid, truncation, crossing_request(grid, own_first, own_end));
  CrossingNorms norms;
  norms.all = concatenate(slabs, &NearSurfaceValues::all);
  norms.kinkless = concatenate(slabs, &NearSurfaceValues::kinkless);
  return norms;
}

GradientNormSummary summarize_gradient_norms(CrossingNorms crossing) {
  GradientNormSummary summary;
  std::vector<double>& norms = crossing.all;
  summary.count = long(norms.size());
  if (norms.size() < 16) return summary;
  auto percentile = [&](std::size_t q) {
    return detail::kth_smallest(norms, norms.size() * q / 100);
  };
  summary.low = percentile(10);
  summary.median = percentile(50);
  summary.high = percentile(90);
  // The points without a kink confirm a rescaling, or veto it; with too few of them, only a
  // field scaled outright is rescaled.
  const bool scaled = crossing.kinkless.size() >= 16
                          ? distance_value_scale(median_of(crossing.kinkless)) != 1
                          : std::abs(summary.median - 1) > kScaledSlope;
  if (scaled) summary.slope = summary.median;
  return summary;
}

GradientNormSummary gradient_norm_summary(const GridView& grid, const Truncation& truncation) {
  return detail::norm_summary_of(
      near_surface_values(grid, truncation, crossing_request(grid, grid.first, grid.whole_dims())));
}

namespace detail {

GradientNormSummary norm_summary_of(const std::vector<NearSurfaceValues>& slabs) {
  std::vector<double> smooth = concatenate(slabs, &NearSurfaceValues::smooth);
  GradientNormSummary summary =
      summarize_gradient_norms({concatenate(slabs, &NearSurfaceValues::all),
                                concatenate(slabs, &NearSurfaceValues::kinkless)});
  if (summary.count > 0) summary.smooth_fraction = double(smooth.size()) / double(summary.count);
  const double scale = distance_value_scale(summary.slope);
  for (double& n : smooth) n = std::abs(n * scale - 1);
  summary.smooth_spread = summarize_gradient_norms({std::move(smooth), {}}).median;
  return summary;
}

}  // namespace detail

double distance_value_scale(double slope) {
  if (!(std::isfinite(slope) && slope > 0 && std::abs(slope - 1) > 0.1)) return 1.0;
  if (!std::isfinite(1 / slope)) {
    // (Subnormal values: their inverse scale overflows, and unscaled they are no distances.)
    std::ostringstream message;
    message << std::setprecision(3) << "the values change by " << slope
            << " per unit length near the surface, too little to scale into distances; "
               "multiply them by a constant";
    throw Error(message.str());
  }
  return 1 / slope;
}

}  // namespace sdfcontour
