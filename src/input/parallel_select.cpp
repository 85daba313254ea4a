#include "input/parallel_select.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

namespace {

// A double's bits, flipped so that their unsigned order is the values' order.
std::uint64_t ordered_bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return (b >> 63) ? ~b : b | (std::uint64_t(1) << 63);
}

double from_ordered_bits(std::uint64_t u) {
  const std::uint64_t b = (u >> 63) ? u & ~(std::uint64_t(1) << 63) : ~u;
  double x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

constexpr int kDigit = 16;
constexpr std::size_t kBins = std::size_t(1) << kDigit;
constexpr std::size_t kChunk = std::size_t(1) << 16;

}  // namespace

double kth_smallest(const std::vector<ValueRun>& runs, std::size_t k) {
  // The runs cut into chunks, so that one long run is counted in parallel too.
  std::vector<ValueRun> chunks;
  std::size_t total = 0;
  for (const ValueRun& r : runs) {
    total += r.size;
    for (std::size_t at = 0; at < r.size; at += kChunk)
      chunks.push_back({r.data + at, std::min(kChunk, r.size - at)});
  }
  if (k >= total) throw InternalError("kth_smallest: a rank beyond the values");
  if (total <= kChunk) {  // (few values: one copy and a selection cost less than the passes)
    std::vector<double> all;
    all.reserve(total);
    for (const ValueRun& r : runs) all.insert(all.end(), r.data, r.data + r.size);
    std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(k), all.end());
    return all[k];
  }
  std::uint64_t prefix = 0;  // the selected value's bits above `shift + kDigit`
  for (int shift = 64 - kDigit; shift >= 0; shift -= kDigit) {
    const std::uint64_t fixed = shift + kDigit >= 64 ? 0 : ~std::uint64_t(0) << (shift + kDigit);
    tbb::enumerable_thread_specific<std::vector<std::size_t>> local(
        [] { return std::vector<std::size_t>(kBins, 0); });
    tbb::parallel_for(std::size_t(0), chunks.size(), [&](std::size_t c) {
      std::vector<std::size_t>& bins = local.local();
      for (std::size_t i = 0; i < chunks[c].size; ++i) {
        const std::uint64_t key = ordered_bits(chunks[c].data[i]);
        if ((key & fixed) == prefix) ++bins[std::size_t(key >> shift) & (kBins - 1)];
      }
    });
    std::vector<std::size_t> bins(kBins, 0);
    for (const auto& l : local)
      for (std::size_t b = 0; b < kBins; ++b) bins[b] += l[b];
    std::size_t bin = 0;
    for (; bin + 1 < kBins && k >= bins[bin]; ++bin) k -= bins[bin];
    prefix |= std::uint64_t(bin) << shift;
  }
  return from_ordered_bits(prefix);
}

}  // namespace sdfcontour::detail
