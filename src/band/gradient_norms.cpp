// The field's gradient norm next to its sign changes: how far the values are from distances.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "input/parallel_select.h"
#include "input/value_scans.h"
#include "input/windowed_passes.h"
#include "sdfcontour/band/band.h"

namespace sdfcontour {

namespace {

// crossing_gradient_norms, with the norms where the field is smooth also in `smooth` (if given).
CrossingNorms crossing_norms(const GridView& grid, const Truncation& truncation,
                             std::array<int, 3> own_first, std::array<int, 3> own_end,
                             std::vector<double>* smooth) {
  const std::array<int, 3> whole = grid.whole_dims();
  std::array<int, 3> from{}, to{};  // block indices of the owned samples measured
  for (int a = 0; a < 3; ++a) {
    from[a] = std::max(own_first[a], 2) - grid.first[a];
    to[a] = std::min(own_end[a], whole[a] - 2) - grid.first[a];
    if (from[a] < to[a] && (from[a] < 2 || to[a] + 2 > grid.dims[a]))
      throw Error("the block must hold 2 samples beyond the samples whose gradients it measures");
  }
  if (from[0] >= to[0] || from[1] >= to[1] || from[2] >= to[2]) return {};
  struct Slab {
    std::vector<double> all, kinkless, smooth;
  };
  const Eigen::Vector3d h = grid.spacing();
  const std::size_t stride[3] = {std::size_t(grid.dims[1]) * std::size_t(grid.dims[2]),
                                 std::size_t(grid.dims[2]), 1};
  std::vector<Slab> per_slab(std::size_t(to[0] - from[0]));
  const bool truncated_anywhere = truncation.detected();
  grid.visit([&](const auto* f) {
    detail::windowed_slabs(grid, f, from[0], to[0], 2, [&](int i) {
      // Only next to a sign change, where a field is read and truncation never reaches: first a
      // row's mask, then its few samples there.
      thread_local std::vector<unsigned char> row_mask;
      row_mask.resize(std::size_t(grid.dims[2]));
      const std::ptrdiff_t beside[4] = {-std::ptrdiff_t(stride[0]), std::ptrdiff_t(stride[0]),
                                        -std::ptrdiff_t(stride[1]), std::ptrdiff_t(stride[1])};
      for (int j = from[1]; j < to[1]; ++j) {
        detail::crossing_row(f + grid.index(i, j, 0), beside, from[2], to[2], row_mask.data());
        for (int k = from[2]; k < to[2]; ++k) {
          if (!row_mask[std::size_t(k)]) continue;
          const std::size_t p = grid.index(i, j, k);
          bool clamped = false;
          if (truncated_anywhere)
            for (int a = 0; a < 3; ++a)
              for (long o : {-2L, -1L, 1L, 2L})
                clamped |= truncation.truncated(double(f[p + o * long(stride[a])]));
          if (clamped) continue;
          // Central differences with steps h and 2h, extrapolated (Richardson): the curvature's
          // O(h^2) bias cancels, so an exact distance measures 1 to O(h^4).
          // (hypot: squares of values as small as 1e-200 would underflow to 0.)
          double d1s[3], d2s[3], bend = 0;
          for (int a = 0; a < 3; ++a) {
            const double minus1 = double(f[p - stride[a]]), plus1 = double(f[p + stride[a]]);
            const double minus2 = double(f[p - 2 * stride[a]]),
                         plus2 = double(f[p + 2 * stride[a]]);
            const double d1 = (plus1 - minus1) / (2 * h[a]);
            const double d2 = (plus2 - minus2) / (4 * h[a]);
            d1s[a] = d1, d2s[a] = d2;
            const double centre = 2 * double(f[p]);
            bend = std::max({bend, std::abs(plus1 - centre + minus1) / h[a],
                             std::abs(plus2 - centre + minus2) / (4 * h[a])});
          }
          const double norm =
              (4 * std::hypot(d1s[0], d1s[1], d1s[2]) - std::hypot(d2s[0], d2s[1], d2s[2])) / 3;
          Slab& slab = per_slab[std::size_t(i - from[0])];
          slab.all.push_back(norm);
          if (bend < kSmoothCurvature) slab.smooth.push_back(norm);
          if (bend < kSmoothCurvature * std::abs(norm)) slab.kinkless.push_back(norm);
        }
      }
    });
  });
  CrossingNorms norms;
  norms.all = detail::concatenate(per_slab, &Slab::all);
  norms.kinkless = detail::concatenate(per_slab, &Slab::kinkless);
  if (smooth) *smooth = detail::concatenate(per_slab, &Slab::smooth);
  return norms;
}

double median_of(const std::vector<double>& v) {
  return detail::kth_smallest(v, v.size() / 2);
}

}  // namespace

CrossingNorms crossing_gradient_norms(const GridView& grid, const Truncation& truncation,
                                      std::array<int, 3> own_first, std::array<int, 3> own_end) {
  return crossing_norms(grid, truncation, own_first, own_end, nullptr);
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
  const std::array<int, 3> end = grid.whole_dims();
  std::vector<double> smooth;
  GradientNormSummary summary =
      summarize_gradient_norms(crossing_norms(grid, truncation, grid.first, end, &smooth));
  if (summary.count > 0) summary.smooth_fraction = double(smooth.size()) / double(summary.count);
  const double scale = distance_value_scale(summary.slope);
  for (double& n : smooth) n = std::abs(n * scale - 1);
  summary.smooth_spread = summarize_gradient_norms({std::move(smooth), {}}).median;
  return summary;
}

double distance_value_scale(double slope) {
  return std::isfinite(slope) && slope > 0 && std::abs(slope - 1) > 0.1 ? 1 / slope : 1.0;
}

}  // namespace sdfcontour
