// Internal: integer keys of octree cells and nodes, and the sorted-key indices every Poisson
// stage looks things up with.
//
// A key packs (i, j, k) with 21 bits each, i highest, so sorting keys sorts by i, then j, then k:
// the keys sharing (i, j) form a "line", and a shifted copy of a sorted list stays sorted (packing
// adds without carries).
#pragma once

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace sdfcontour::poisson {

using Key = std::uint64_t;
constexpr int kKeyBits = 21;
constexpr Key kKeyMask = (Key(1) << kKeyBits) - 1;

inline Key pack(long i, long j, long k) {
  return (Key(i) << (2 * kKeyBits)) | (Key(j) << kKeyBits) | Key(k);
}
inline std::array<long, 3> unpack(Key key) {
  return {long(key >> (2 * kKeyBits)), long((key >> kKeyBits) & kKeyMask), long(key & kKeyMask)};
}

/// An open-addressing map from keys to their position in a key array.
class KeyIndex {
 public:
  KeyIndex() = default;
  explicit KeyIndex(const std::vector<Key>& keys);
  /// Position of key, or -1.
  int find(Key key) const {
    if (slots_.empty()) return -1;
    for (std::size_t h = hash(key) & mask_;; h = (h + 1) & mask_) {
      if (slots_[h].first == key) return slots_[h].second;
      if (slots_[h].first == kEmpty) return -1;
    }
  }

 private:
  static constexpr Key kEmpty = ~Key(0);
  static std::size_t hash(Key x) {  // splitmix64 finaliser
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    return std::size_t(x ^ (x >> 31));
  }
  std::vector<std::pair<Key, int>> slots_;
  std::size_t mask_ = 0;
};

/// Positions in a sorted key array, found through its lines: the line's number from a table, then
/// a binary search inside the line. The table is dense over the lines' bounding rectangle of
/// (i, j) when that is at most a few times the line count (an octree level's lines fill most of
/// their rectangle: 4 bytes per (i, j)), else a hash of the line keys (16 bytes a slot at half
/// load).
class LineIndex {
 public:
  LineIndex() = default;
  explicit LineIndex(const std::vector<Key>& keys);
  /// Position of key in keys (the array this was built from), or -1.
  int find(const std::vector<Key>& keys, Key key) const {
    const int line = line_number(long(key >> (2 * kKeyBits)), long((key >> kKeyBits) & kKeyMask));
    if (line < 0) return -1;
    const auto first = keys.begin() + start_[std::size_t(line)],
               last = keys.begin() + start_[std::size_t(line) + 1];
    const auto it = std::lower_bound(first, last, key);
    return it != last && *it == key ? int(it - keys.begin()) : -1;
  }
  /// Range [first, last) of line (i, j), empty if it has no keys (or i, j lie outside [0, 2^21)).
  std::array<std::uint32_t, 2> line(long i, long j) const {
    const int l = line_number(i, j);
    if (l < 0) return {0, 0};
    return {start_[std::size_t(l)], start_[std::size_t(l) + 1]};
  }
  /// The lines in key order: line l is [start(l), start(l + 1)).
  std::size_t count() const { return start_.empty() ? 0 : start_.size() - 1; }
  std::uint32_t start(std::size_t l) const { return start_[l]; }

 private:
  int line_number(long i, long j) const {
    if (!dense_.empty()) {
      if (i < i0_ || j < j0_ || i >= i0_ + width_ || j >= j0_ + height_) return -1;
      return dense_[std::size_t((i - i0_) * height_ + (j - j0_))];
    }
    if (i < 0 || j < 0 || i > long(kKeyMask) || j > long(kKeyMask)) return -1;
    return lines_.find(pack(0, i, j));
  }
  long i0_ = 0, j0_ = 0, width_ = 0, height_ = 0;
  std::vector<int> dense_;  ///< line number per (i, j) of the rectangle, -1 for none
  KeyIndex lines_;          ///< used when dense_ is empty
  std::vector<std::uint32_t> start_;
};

/// Finds keys of one line of a sorted key array by moving a cursor: cheap when successive keys are
/// close, as when a line of one array is swept against a line of another.
class LineCursor {
 public:
  LineCursor() = default;
  LineCursor(const std::vector<Key>& keys, std::array<std::uint32_t, 2> range)
      : keys_(keys.data()), first_(range[0]), at_(range[0]), last_(range[1]) {}
  /// Position of key, or -1.
  int find(Key key) {
    while (at_ < last_ && keys_[at_] < key) ++at_;
    while (at_ > first_ && keys_[at_ - 1] >= key) --at_;
    return at_ < last_ && keys_[at_] == key ? int(at_) : -1;
  }

 private:
  const Key* keys_ = nullptr;
  std::uint32_t first_ = 0, at_ = 0, last_ = 0;
};

/// Calls f(i, j, first, last) for each line [first, last) of a sorted key array (the keys with
/// that i and j), lines in parallel.
template <class F>
void for_each_line(const LineIndex& lines, const std::vector<Key>& keys, F&& f) {
  tbb::parallel_for(std::size_t(0), lines.count(), [&](std::size_t line) {
    const std::size_t first = lines.start(line);
    const auto key = unpack(keys[first]);
    f(key[0], key[1], first, std::size_t(lines.start(line + 1)));
  });
}

/// Sorts keys and drops repeats.
void sort_unique(std::vector<Key>& keys);

/// The sorted union of keys + (a, b, c) over a in [from[0], to[0]], b in [from[1], to[1]], c in
/// [from[2], to[2]], coordinates kept in [0, limit], for sorted keys. Memory: the output and one
/// intermediate list, never a copy per shift.
std::vector<Key> shifted_union(const std::vector<Key>& keys, const std::array<long, 3>& from,
                               const std::array<long, 3>& to, long limit);

/// The sorted keys of all cells within `radius` of the given sorted cells (a cube per cell), with
/// coordinates kept in [0, limit].
std::vector<Key> dilate(const std::vector<Key>& keys, long radius, long limit);

/// Morton code of a cell (interleaved index bits, x lowest): the cells of a coarser depth are runs
/// of consecutive codes at a finer one.
Key morton(const std::array<long, 3>& cell);
/// The cell of a Morton code.
std::array<long, 3> morton_cell(Key code);

}  // namespace sdfcontour::poisson
