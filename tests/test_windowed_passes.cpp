// Whole-grid passes over a grid whose pages can be dropped (windowed_passes.h): the same results
// as over the plain grid, and every value handed to the dropper once the passes are done.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "input/windowed_passes.h"
#include "pipeline/grid_measures.h"
#include "sdfcontour/band/band.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/noise.h"
#include "sdfcontour/input/signed_distance.h"

using namespace sdfcontour;

namespace {

// A float32 view of `values` whose dropper records the value ranges it is handed.
struct RecordingView {
  std::vector<float> values;
  std::vector<std::pair<std::size_t, std::size_t>> dropped;  // [first, last) value indices
  std::function<void(const void*, std::size_t)> drop;
  GridView view;

  RecordingView(const Grid& g, bool dropping)
      : values(g.values.data(), g.values.data() + g.size()) {
    view = view_of(g);
    view.data = values.data();
    view.type = ScalarType::Float32;
    drop = [this](const void* address, std::size_t bytes) {
      const std::size_t first = std::size_t(static_cast<const float*>(address) - values.data());
      dropped.emplace_back(first, first + bytes / sizeof(float));
    };
    if (dropping) view.drop_pages = &drop;
  }
  // Whether the dropped ranges cover every value.
  bool all_dropped() const {
    auto ranges = dropped;
    std::sort(ranges.begin(), ranges.end());
    std::size_t reach = 0;
    for (const auto& [first, last] : ranges) {
      if (first > reach) return false;
      reach = std::max(reach, last);
    }
    return reach >= values.size();
  }
};

}  // namespace

TEST(WindowedPasses, DroppingPagesChangesNoResult) {
  // A torus at 72^3 truncated at 3 spacings: 373,248 values, windows of 65,536 values (5.7 of
  // them) and of 12 slabs.
  const int n = 72;
  const double h = 2.0 / (n - 1);
  const Grid g = sample_grid_truncated(*make_builtin_shape("torus"), n, Bounds{}, 3 * h);
  ASSERT_GT(g.size(), 5 * (std::size_t(1) << 16));
  RecordingView plain(g, false), dropping(g, true);
  EXPECT_FALSE(first_non_finite(dropping.view).has_value());
  EXPECT_TRUE(dropping.all_dropped());
  EXPECT_GT(dropping.dropped.size(), std::size_t(5));

  const Truncation t = detect_truncation(plain.view), td = detect_truncation(dropping.view);
  EXPECT_TRUE(t.detected());
  EXPECT_EQ(t.inside, td.inside);
  EXPECT_EQ(t.outside, td.outside);

  dropping.dropped.clear();
  const GradientNormSummary s = gradient_norm_summary(plain.view, t),
                            sd = gradient_norm_summary(dropping.view, t);
  EXPECT_GT(s.count, 1000);
  EXPECT_EQ(s.count, sd.count);
  EXPECT_EQ(s.median, sd.median);
  EXPECT_EQ(s.low, sd.low);
  EXPECT_EQ(s.high, sd.high);
  EXPECT_TRUE(dropping.all_dropped());
  EXPECT_GT(dropping.dropped.size(), std::size_t(1));

  const double noise = noise_level(plain.view, t);
  EXPECT_TRUE(std::isfinite(noise));
  EXPECT_EQ(noise, noise_level(dropping.view, t));
}

TEST(WindowedPasses, FindsTheFirstBadValueAndTheSignChangeAlike) {
  const Grid g = sample_grid(*make_builtin_shape("sphere"), 72, Bounds{});
  RecordingView plain(g, false), dropping(g, true);
  // A NaN late in the grid (past the first windows) and an infinity after it.
  for (RecordingView* v : {&plain, &dropping}) {
    v->values[300000] = NAN;
    v->values[350000] = INFINITY;
  }
  const auto bad = first_non_finite(plain.view);
  ASSERT_TRUE(bad.has_value());
  EXPECT_EQ(bad, first_non_finite(dropping.view));
  EXPECT_EQ(g.index((*bad)[0], (*bad)[1], (*bad)[2]), std::size_t(300000));
  // The pass stops at the window holding it: the last values are never read nor dropped.
  EXPECT_FALSE(dropping.all_dropped());

  RecordingView outside(g, true);
  EXPECT_NO_THROW(require_sign_change(outside.view));
  for (float& v : outside.values) v = std::abs(v) + 0.5f;
  EXPECT_THROW(require_sign_change(outside.view), Error);
  EXPECT_TRUE(outside.all_dropped());
}

// The first bad value of a float32 and a float64 grid, found block by block: every finite float
// passes (the largest one too), an infinity or NaN of either sign does, and so does a double
// beyond 1e100; the first one in the grid's order wins, across and within blocks.
TEST(WindowedPasses, FirstNonFiniteTakesEveryFiniteFloatAndTheFirstBadValue) {
  const Grid g = sample_grid(*make_builtin_shape("sphere"), 24, Bounds{});
  RecordingView f(g, false);
  f.values[7] = std::numeric_limits<float>::max();
  f.values[2000] = -std::numeric_limits<float>::max();
  f.values[5000] = std::numeric_limits<float>::denorm_min();
  EXPECT_FALSE(first_non_finite(f.view).has_value());
  f.values[4100] = NAN;
  f.values[4099] = -INFINITY;
  f.values[9000] = INFINITY;
  auto bad = first_non_finite(f.view);
  ASSERT_TRUE(bad.has_value());
  EXPECT_EQ(g.index((*bad)[0], (*bad)[1], (*bad)[2]), std::size_t(4099));

  Grid d = g;
  d.values[11] = 1e99;
  EXPECT_FALSE(first_non_finite(view_of(d)).has_value());
  d.values[3333] = -1e101;
  d.values[3334] = NAN;
  bad = first_non_finite(view_of(d));
  ASSERT_TRUE(bad.has_value());
  EXPECT_EQ(g.index((*bad)[0], (*bad)[1], (*bad)[2]), std::size_t(3333));
}

// measure_grid reads the gradient norms and the noise in one pass: the same numbers as their own
// passes, and the noise as a brute-force median of the fourth differences finds it, on a
// truncated, noisy torus (stencils that touch a clamped value left out).
TEST(WindowedPasses, OnePassMeasuresEqualTheirOwnPassesAndABruteForceNoise) {
  const int n = 48;
  const double h = 2.0 / (n - 1);
  Grid g = sample_grid_truncated(*make_builtin_shape("torus"), n, Bounds{}, 3 * h);
  std::uint32_t state = 12345;  // a fixed LCG: noise of about 0.02 h on the unclamped values
  const double t0 = g.values.maxCoeff();
  for (Eigen::Index i = 0; i < g.values.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    if (std::abs(g.values[i]) < 0.9 * t0)
      g.values[i] += 0.04 * h * (double(state >> 8) / 16777216.0 - 0.5);
  }
  for (bool dropping : {false, true}) {
    RecordingView grid(g, dropping);
    ContourOptions options;
    const detail::GridMeasures m = detail::measure_grid(grid.view, options);
    ASSERT_TRUE(m.truncation.detected());
    const GradientNormSummary s = gradient_norm_summary(grid.view, m.truncation);
    EXPECT_GT(s.count, 500);
    EXPECT_EQ(m.gradient_norms.count, s.count);
    EXPECT_EQ(m.gradient_norms.median, s.median);
    EXPECT_EQ(m.gradient_norms.low, s.low);
    EXPECT_EQ(m.gradient_norms.high, s.high);
    EXPECT_EQ(m.gradient_norms.smooth_fraction, s.smooth_fraction);
    EXPECT_EQ(m.gradient_norms.smooth_spread, s.smooth_spread);
    const double noise = noise_level(grid.view, m.truncation);
    EXPECT_EQ(m.noise, noise / h);  // (a slope near 1: no rescaling)

    std::vector<double> d4;
    const long stride[3] = {long(n) * n, long(n), 1};
    for (int i = 2; i < n - 2; ++i)
      for (int j = 2; j < n - 2; ++j)
        for (int k = 2; k < n - 2; ++k) {
          const long p = long(g.index(i, j, k));
          if (!(std::abs(double(grid.values[std::size_t(p)])) < 3 * h)) continue;
          for (int a = 0; a < 3; ++a) {
            double sum = 0;
            bool clamped = false;
            for (int o = -2; o <= 2; ++o) {
              const double v = grid.values[std::size_t(p + o * stride[a])];
              clamped |= m.truncation.truncated(v);
              sum += (o == 0 ? 6.0 : std::abs(o) == 1 ? -4.0 : 1.0) * v;
            }
            if (!clamped) d4.push_back(std::abs(sum));
          }
        }
    ASSERT_GT(d4.size(), std::size_t(1000));
    std::nth_element(d4.begin(), d4.begin() + long(d4.size() / 2), d4.end());
    EXPECT_DOUBLE_EQ(noise, 1.4826 * d4[d4.size() / 2] / std::sqrt(70.0));
    EXPECT_NEAR(noise / h, 0.04 / std::sqrt(12.0), 0.01);  // the uniform noise's deviation
  }
}
