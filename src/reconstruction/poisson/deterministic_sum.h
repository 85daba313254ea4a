// Internal: parallel sums whose result does not depend on the thread count.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace sdfcontour::poisson {

/// Sums over [0, n): f(i, sums) adds element i's terms to N running sums. Chunks of fixed size
/// run in parallel and their sums are added in chunk order, so the result does not depend on the
/// thread count. f may also write element i's own outputs (it runs once per element).
template <std::size_t N, class F>
std::array<double, N> deterministic_sums(std::size_t n, F&& f) {
  constexpr std::size_t kChunk = 1 << 12;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::array<double, N>> partial(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    std::array<double, N> sums{};
    for (std::size_t i = c * kChunk, e = std::min(n, i + kChunk); i < e; ++i) f(i, sums);
    partial[c] = sums;
  });
  std::array<double, N> total{};
  for (const auto& sums : partial)
    for (std::size_t q = 0; q < N; ++q) total[q] += sums[q];
  return total;
}

/// Sum of f(i) over [0, n), independent of the thread count.
template <class F>
double deterministic_sum(std::size_t n, F&& f) {
  return deterministic_sums<1>(n,
                               [&](std::size_t i, std::array<double, 1>& s) { s[0] += f(i); })[0];
}

}  // namespace sdfcontour::poisson
