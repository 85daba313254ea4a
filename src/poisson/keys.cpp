#include "keys.h"

#include <iterator>

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
  for (std::size_t v = 0; v < keys.size(); ++v)
    if (v == 0 || keys[v] >> kKeyBits != keys[v - 1] >> kKeyBits) {
      line_keys.push_back(keys[v] >> kKeyBits);
      start_.push_back(std::uint32_t(v));
    }
  start_.push_back(std::uint32_t(keys.size()));
  lines_ = KeyIndex(line_keys);
}

void sort_unique(std::vector<Key>& keys) {
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

std::vector<Key> merge_sorted(std::vector<std::vector<Key>> lists) {
  while (lists.size() > 1) {
    std::vector<std::vector<Key>> merged((lists.size() + 1) / 2);
    tbb::parallel_for(std::size_t(0), lists.size() / 2, [&](std::size_t pair) {
      const auto &a = lists[2 * pair], &b = lists[2 * pair + 1];
      merged[pair].reserve(a.size() + b.size());
      std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(merged[pair]));
    });
    if (lists.size() % 2) merged.back() = std::move(lists.back());
    lists = std::move(merged);
  }
  return lists.empty() ? std::vector<Key>() : std::move(lists[0]);
}

std::vector<Key> dilate(std::vector<Key> keys, long radius, long limit) {
  // Along i and j: shifted copies of a sorted list stay sorted, so they are merged, not sorted.
  for (int axis = 0; axis < 2; ++axis) {
    const int shift = axis == 0 ? 2 * kKeyBits : kKeyBits;
    std::vector<std::vector<Key>> lists(std::size_t(2 * radius + 1));
    tbb::parallel_for(long(0), 2 * radius + 1, [&](long q) {
      const long offset = q - radius;
      auto& out = lists[std::size_t(q)];
      out.reserve(keys.size());
      for (Key key : keys) {
        const long c = long((key >> shift) & kKeyMask) + offset;
        if (c >= 0 && c <= limit)
          out.push_back(offset >= 0 ? key + (Key(offset) << shift) : key - (Key(-offset) << shift));
      }
    });
    keys = merge_sorted(std::move(lists));
  }
  // Along k, within a line, the union of the intervals [k - radius, k + radius] comes out sorted
  // in one pass.
  std::vector<Key> out;
  out.reserve(keys.size() + keys.size() / 2);
  for (std::size_t v = 0; v < keys.size(); ++v) {
    const Key line = keys[v] & ~kKeyMask;
    const long k = long(keys[v] & kKeyMask);
    long from = std::max(k - radius, 0L);
    if (!out.empty() && (out.back() & ~kKeyMask) == line)
      from = std::max(from, long(out.back() & kKeyMask) + 1);
    for (long c = from; c <= std::min(k + radius, limit); ++c) out.push_back(line | Key(c));
  }
  return out;
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
