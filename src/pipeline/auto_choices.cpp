// The automatic choices that follow the samples per axis (declared in pipeline.h), and what
// contour() reads from a grid with given options.
#include <algorithm>

#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour {

int auto_poisson_depth(const PointMatrix& points, double spacing) {
  if (points.rows() == 0 || !(spacing > 0)) return 8;
  const double extent = (points.colwise().maxCoeff() - points.colwise().minCoeff()).maxCoeff();
  const double samples_per_axis = extent / spacing + 1;
  if (samples_per_axis > 513) return 11;
  if (samples_per_axis > 257) return 10;
  if (samples_per_axis > 129) return 9;
  return samples_per_axis > 48 ? 8 : 7;
}

bool auto_local_reconstruction(double /*samples_per_axis*/) {
  return true;
}

bool auto_lattice_points(double samples_per_axis) {
  return samples_per_axis >= 64;
}

int auto_subdivisions(double samples_per_axis) {
  return samples_per_axis < 64 ? 2 : 1;
}

double auto_split_sag(double samples_per_axis) {
  // One uniform level where two were (64-95): a finer split keeps the sag it would leave.
  return samples_per_axis >= 64 && samples_per_axis < 96 ? 0.002 : 0.004;
}

bool auto_thin_parts(double samples_per_axis) {
  return samples_per_axis < 192;
}

bool thin_parts_need_gaps(double samples_per_axis) {
  return !auto_thin_parts(samples_per_axis) && samples_per_axis <= kThinPartGridLimit;
}

bool auto_thin_parts(double samples_per_axis, const SubspacingGaps& gaps) {
  if (!thin_parts_need_gaps(samples_per_axis)) return auto_thin_parts(samples_per_axis);
  return gaps.gaps > 0 && double(gaps.gaps) >= kThinPartGapShare * double(gaps.crossings);
}

bool auto_edge_fans(double samples_per_axis) {
  return samples_per_axis >= kEdgeFansFrom;
}

ContourOptions with_edge_fans(ContourOptions options, double samples_per_axis) {
  options.local.edge_fans = options.edge_fans == Switch::On ||
                            (options.edge_fans == Switch::Auto &&
                             (options.local.edge_fans || auto_edge_fans(samples_per_axis)));
  return options;
}

bool auto_sign_constraints(double samples_per_axis) {
  return samples_per_axis < 128;
}

double auto_carving_band(const BandOptions& given, double samples_per_axis) {
  // Every sample within 16 spacings, not only the band's 8: the farther balls are large (64^3:
  // wingnut and hammer 6-7% lower L1, bunny 1%; every sample gains little more;
  // docs/carving.md). Finer grids gain less for more.
  constexpr double kCarvingBand = 16;
  return given.band == 0 && samples_per_axis < 128 ? kCarvingBand : 0.0;
}

bool auto_carve_sides(double samples_per_axis) {
  return samples_per_axis < 128;
}

bool auto_approximate_distances(const GradientNormSummary& norms) {
  constexpr double kApproximateSpread = 0.02, kSmoothShare = 0.2;
  return norms.smooth_spread > kApproximateSpread && norms.smooth_fraction >= kSmoothShare;
}

double contour_values_reach(const ContourOptions& options, const std::array<int, 3>& dims) {
  const double samples_per_axis = *std::max_element(dims.begin(), dims.end());
  const BandOptions& band = options.band;
  const double reach = (band.band > 0 ? band.band : auto_band(samples_per_axis)) + band.margin;
  if (options.method != Method::Gcp || options.carve == Switch::Off) return reach;
  return std::max(reach, auto_carving_band(band, samples_per_axis));
}

}  // namespace sdfcontour
