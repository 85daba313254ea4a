// The parallel radix selection (parallel_select.h) against std::nth_element.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "input/parallel_select.h"
#include "sdfcontour/types.h"

using namespace sdfcontour;

TEST(ParallelSelect, AgreesWithNthElementOverRuns) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0, 1);
  std::uniform_int_distribution<int> few(0, 5);
  // Runs of unlike lengths (one past the chunk size, some empty) with negatives, repeats, zeros,
  // infinities and values a few bits apart.
  std::vector<std::vector<double>> runs(6);
  const std::size_t lengths[6] = {0, 1, 3000, 65537, 17, 120000};
  for (std::size_t r = 0; r < runs.size(); ++r)
    for (std::size_t i = 0; i < lengths[r]; ++i) {
      const int kind = few(rng);
      runs[r].push_back(kind == 0   ? 0.0
                        : kind == 1 ? double(few(rng))
                        : kind == 2 ? std::nextafter(1.0, 2.0 + few(rng))
                                    : normal(rng) * std::pow(10.0, few(rng) - 2));
    }
  runs[2][5] = std::numeric_limits<double>::infinity();
  runs[5][9] = -std::numeric_limits<double>::infinity();
  std::vector<detail::ValueRun> view;
  std::vector<double> all;
  for (const auto& r : runs) {
    view.push_back({r.data(), r.size()});
    all.insert(all.end(), r.begin(), r.end());
  }
  for (std::size_t k : {std::size_t(0), std::size_t(1), all.size() / 10, all.size() / 2,
                        all.size() * 9 / 10, all.size() - 1}) {
    std::vector<double> sorted = all;
    std::nth_element(sorted.begin(), sorted.begin() + long(k), sorted.end());
    EXPECT_EQ(detail::kth_smallest(view, k), sorted[k]) << "rank " << k;
  }
  EXPECT_EQ(detail::kth_smallest(all, all.size() / 2), detail::kth_smallest(view, all.size() / 2));
}

TEST(ParallelSelect, FewValuesAsManyValues) {
  // Below and above the count where the radix passes begin (65,536 values).
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0, 1);
  for (std::size_t n : {std::size_t(5), std::size_t(65536), std::size_t(65537)}) {
    std::vector<double> v(n);
    for (double& x : v) x = normal(rng);
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t k : {std::size_t(0), n / 3, n - 1})
      EXPECT_EQ(detail::kth_smallest(v, k), sorted[k]) << n << " values, rank " << k;
  }
}

TEST(ParallelSelect, ARankBeyondTheValuesIsABug) {
  const std::vector<double> v{1, 2, 3};
  EXPECT_THROW(detail::kth_smallest(v, 3), InternalError);
  EXPECT_EQ(detail::kth_smallest(v, 2), 3.0);
}
