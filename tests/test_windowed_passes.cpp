// Whole-grid passes over a grid whose pages can be dropped (windowed_passes.h): the same results
// as over the plain grid, and every value handed to the dropper once the passes are done.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "input/windowed_passes.h"
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
