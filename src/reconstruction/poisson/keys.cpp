#include "reconstruction/poisson/keys.h"

#include <iterator>
#include <limits>

namespace sdfcontour::poisson {

KeyIndex::KeyIndex(const std::vector<Key>& keys) {
  std::size_t capacity = 16;
  while (capacity < 2 * keys.size()) capacity *= 2;
  mask_ = capacity - 1;
  slots_.assign(capacity, {kEmpty, -1});
  for (std::size_t i = 0; i < keys.size(); ++i) {
    std::size_t h = hash(keys[i]) & mask_;
    while (slots_[h].first != kEmpty) h = (h + 1) & mask_;
    slots_[h] = {keys[i], int(i)};
  }
}

LineIndex::LineIndex(const std::vector<Key>& keys) {
  std::vector<Key> line_keys;
  long j_min = long(kKeyMask), j_max = 0;
  for (std::size_t v = 0; v < keys.size(); ++v)
    if (v == 0 || keys[v] >> kKeyBits != keys[v - 1] >> kKeyBits) {
      line_keys.push_back(keys[v] >> kKeyBits);
      start_.push_back(std::uint32_t(v));
      const long j = long(line_keys.back() & kKeyMask);
      j_min = std::min(j_min, j), j_max = std::max(j_max, j);
    }
  start_.push_back(std::uint32_t(keys.size()));
  if (line_keys.empty()) return;
  const long i_min = long(line_keys.front() >> kKeyBits),
             i_max = long(line_keys.back() >> kKeyBits);
  const std::size_t area = std::size_t(i_max - i_min + 1) * std::size_t(j_max - j_min + 1);
  if (area <= 4 * line_keys.size() + 4096) {
    i0_ = i_min, j0_ = j_min, width_ = i_max - i_min + 1, height_ = j_max - j_min + 1;
    dense_.assign(area, -1);
    for (std::size_t l = 0; l < line_keys.size(); ++l)
      dense_[std::size_t((long(line_keys[l] >> kKeyBits) - i0_) * height_ +
                         (long(line_keys[l] & kKeyMask) - j0_))] = int(l);
  } else {
    lines_ = KeyIndex(line_keys);
  }
}

void sort_unique(std::vector<Key>& keys) {
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

namespace {

// The sorted union of the keys shifted by `from`..`to` along the axis at bit `shift` (i: 42, j:
// 21), dropping keys whose coordinate leaves [0, limit]. A shifted copy of a sorted list stays
// sorted (packing adds without carries), so this is a merge of cursors over one array, never
// copied: chunks of the output key range run in parallel, counted first, then written in place.
std::vector<Key> union_of_shifts(const std::vector<Key>& keys, int shift, long from, long to,
                                 long limit) {
  using Signed = std::int64_t;
  const int ways = int(to - from + 1);
  auto offset = [&](int w) { return Signed(from + w) * (Signed(1) << shift); };
  auto valid = [&](Key key, int w) {
    const long c = long((key >> shift) & kKeyMask) + from + w;
    return c >= 0 && c <= limit;
  };
  // Chunk t covers output keys [bound[t], bound[t + 1]); bounds from the input's quantiles.
  const std::size_t chunks =
      std::max<std::size_t>(1, std::min<std::size_t>(keys.size() / 4096, 256));
  std::vector<Signed> bound(chunks + 1);
  bound[0] = std::numeric_limits<Signed>::min();
  bound[chunks] = std::numeric_limits<Signed>::max();
  for (std::size_t t = 1; t < chunks; ++t) bound[t] = Signed(keys[keys.size() * t / chunks]);
  // Runs chunk t's merge, calling emit(key) for each distinct output key in order.
  auto merge_chunk = [&](std::size_t t, auto&& emit) {
    std::vector<std::size_t> at(static_cast<std::size_t>(ways));
    for (int w = 0; w < ways; ++w)
      at[std::size_t(w)] = std::size_t(
          std::lower_bound(keys.begin(), keys.end(), bound[t],
                           [&](Key key, Signed b) { return Signed(key) + offset(w) < b; }) -
          keys.begin());
    bool any = false;
    Signed last = 0;
    for (;;) {
      Signed best = bound[t + 1];
      for (int w = 0; w < ways; ++w) {
        std::size_t& a = at[std::size_t(w)];
        while (a < keys.size() && !valid(keys[a], w)) ++a;
        if (a < keys.size()) best = std::min(best, Signed(keys[a]) + offset(w));
      }
      if (best >= bound[t + 1]) break;
      if (!any || best != last) emit(Key(best));
      any = true, last = best;
      for (int w = 0; w < ways; ++w) {
        std::size_t& a = at[std::size_t(w)];
        if (a < keys.size() && Signed(keys[a]) + offset(w) == best) ++a;
      }
    }
  };
  std::vector<std::size_t> start(chunks + 1, 0);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t t) {
    std::size_t count = 0;
    merge_chunk(t, [&](Key) { ++count; });
    start[t + 1] = count;
  });
  for (std::size_t t = 0; t < chunks; ++t) start[t + 1] += start[t];
  std::vector<Key> out(start[chunks]);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t t) {
    std::size_t next = start[t];
    merge_chunk(t, [&](Key key) { out[next++] = key; });
  });
  return out;
}

// The sorted union, within each line (fixed i, j), of [k + from, k + to] over its keys, kept in
// [0, limit]: one pass, since the intervals come in order.
std::vector<Key> union_along_k(const std::vector<Key>& keys, long from, long to, long limit) {
  std::vector<Key> out;
  out.reserve(keys.size() + keys.size() / 2);
  for (std::size_t v = 0; v < keys.size(); ++v) {
    const Key line = keys[v] & ~kKeyMask;
    const long k = long(keys[v] & kKeyMask);
    long first = std::max(k + from, 0L);
    if (!out.empty() && (out.back() & ~kKeyMask) == line)
      first = std::max(first, long(out.back() & kKeyMask) + 1);
    for (long c = first; c <= std::min(k + to, limit); ++c) out.push_back(line | Key(c));
  }
  return out;
}

}  // namespace

std::vector<Key> shifted_union(const std::vector<Key>& keys, const std::array<long, 3>& from,
                               const std::array<long, 3>& to, long limit) {
  std::vector<Key> out = union_along_k(keys, from[2], to[2], limit);
  out = union_of_shifts(out, kKeyBits, from[1], to[1], limit);
  return union_of_shifts(out, 2 * kKeyBits, from[0], to[0], limit);
}

std::vector<Key> dilate(const std::vector<Key>& keys, long radius, long limit) {
  return shifted_union(keys, {-radius, -radius, -radius}, {radius, radius, radius}, limit);
}

namespace {

Key spread_bits(long v) {
  Key x = Key(v) & 0xffff;
  x = (x | (x << 16)) & 0x0000ff0000ffULL;
  x = (x | (x << 8)) & 0x00f00f00f00fULL;
  x = (x | (x << 4)) & 0x0c30c30c30c3ULL;
  x = (x | (x << 2)) & 0x249249249249ULL;
  return x;
}

long compact_bits(Key x) {
  x &= 0x249249249249ULL;
  x = (x | (x >> 2)) & 0x0c30c30c30c3ULL;
  x = (x | (x >> 4)) & 0x00f00f00f00fULL;
  x = (x | (x >> 8)) & 0x0000ff0000ffULL;
  x = (x | (x >> 16)) & 0xffff;
  return long(x);
}

}  // namespace

Key morton(const std::array<long, 3>& cell) {
  return spread_bits(cell[0]) | spread_bits(cell[1]) << 1 | spread_bits(cell[2]) << 2;
}

std::array<long, 3> morton_cell(Key code) {
  return {compact_bits(code), compact_bits(code >> 1), compact_bits(code >> 2)};
}

}  // namespace sdfcontour::poisson
