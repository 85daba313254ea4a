#include "pipeline/grid_measures.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "band/near_surface.h"
#include "sdfcontour/input/noise.h"

namespace sdfcontour::detail {

GridMeasures measure_grid(const GridView& grid, const ContourOptions& options) {
  validate_grid(grid);
  GridMeasures m;
  const Truncation truncation = m.truncation = resolve_truncation(grid, options.band);
  // The gradient norms and the noise from one read of the grid where it is whole (their samples
  // are then the same: 2 or more from its sides).
  double noise = 0;
  if (grid.first == std::array<int, 3>{0, 0, 0} && grid.dims == grid.whole_dims()) {
    const std::vector<NearSurfaceValues> slabs =
        whole_grid_near_surface(grid, truncation, true, true);
    m.gradient_norms = norm_summary_of(slabs);
    noise = noise_of(slabs);
  } else {
    m.gradient_norms = gradient_norm_summary(grid, truncation);
    noise = noise_level(grid, truncation);
  }
  const double slope = m.gradient_norms.median;
  const double scale = std::isfinite(slope) && slope > 0 && std::abs(slope - 1) > 0.5 ? slope : 1;
  m.noise = noise / scale / grid.spacing().maxCoeff();
  return m;
}

bool clamped_too_close(const GridMeasures& measured, double spacing) {
  const Truncation& t = measured.truncation;
  const double slope = measured.gradient_norms.slope > 0 ? measured.gradient_norms.slope : 1.0;
  return t.detected() && std::max(t.inside, t.outside) / slope <= kClampedTooClose * spacing;
}

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

}  // namespace sdfcontour::detail
