// Internal: boxes (a mesh's triangles) listed per cell of a uniform grid that they meet, for the
// nearest-triangle queries and the self-intersection search.
#pragma once

#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "pipeline/uninitialised_allocator.h"

namespace sdfcontour::detail {

/// Cubes of side `cell` from `origin`, `n` of them per axis.
struct CellGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double cell = 1;
  std::array<int, 3> n{1, 1, 1};

  /// The grid over [lo, hi] with cubes of side `cell` or, where that would make more than
  /// `most_columns` columns (i, j) or 2^30 cubes along an axis, the least power of two times it
  /// that does not; one cube of infinite side where the box or `cell` is not finite.
  static CellGrid over(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double cell,
                       double most_columns);

  /// The cube along axis a that holds x (clamped to the grid; NaN: the first).
  int index(double x, int a) const {
    const double u = std::floor((x - origin[a]) / cell);
    return !(u > 0) ? 0 : (u >= n[std::size_t(a)] - 1 ? n[std::size_t(a)] - 1 : int(u));
  }
  std::array<int, 3> cube_of(const Eigen::Vector3d& x) const {
    return {index(x[0], 0), index(x[1], 1), index(x[2], 2)};
  }
};

/// Boxes 0..count-1 listed in every cube of a CellGrid that they meet (given as ranges of cubes),
/// in columns (i, j) of entries sorted by (k, box). A query visits each box once: at the lowest
/// cube of its range within the cubes read (the maximum of the two ranges' lowest corners).
/// Where the grid has many more columns than boxes (parts far apart), only the occupied columns
/// are kept, found by a binary search.
class TriangleCells {
 public:
  struct Range {
    std::array<int, 3> lo, hi;
  };

  /// ranges[b]: the cubes that box b meets (within the grid).
  TriangleCells(const CellGrid& grid, const std::vector<Range>& ranges);

  const CellGrid& grid() const { return grid_; }
  Range range(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
    return {grid_.cube_of(lo), grid_.cube_of(hi)};
  }

  /// Calls f(b) once for every box b listed in the cubes of r.
  template <class F>
  void for_each_in(const Range& r, F&& f) const {
    for (int i = r.lo[0]; i <= r.hi[0]; ++i)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j) {
        const auto [from, to] =
            column_entries(std::size_t(i) * std::size_t(grid_.n[1]) + std::size_t(j));
        const auto last = entries_.begin() + std::ptrdiff_t(to);
        auto it =
            std::lower_bound(entries_.begin() + std::ptrdiff_t(from), last, Entry{r.lo[2], -1});
        for (; it != last && it->k <= r.hi[2]; ++it) {
          const std::array<int, 3>& first = lowest_[std::size_t(it->box)];
          if (std::max(first[0], r.lo[0]) == i && std::max(first[1], r.lo[1]) == j &&
              std::max(first[2], r.lo[2]) == it->k)
            f(it->box);
        }
      }
  }

  /// Calls f(a, b), a < b, once for every two boxes listed in a common cube (from the lowest
  /// cube they share), in parallel: cube by cube, with no search for the cubes.
  template <class F>
  void for_each_pair(F&& f) const {
    const std::size_t slots = column_start_.size() - 1;
    tbb::parallel_for(std::size_t(0), slots, [&](std::size_t slot) {
      const std::size_t column = sparse_ ? occupied_[slot] : slot;
      const int i = int(column / std::size_t(grid_.n[1])),
                j = int(column % std::size_t(grid_.n[1]));
      const std::size_t last = column_start_[slot + 1];
      for (std::size_t start = column_start_[slot], end; start < last; start = end) {
        const int k = entries_[start].k;
        for (end = start + 1; end < last && entries_[end].k == k;) ++end;
        for (std::size_t a = start; a < end; ++a) {
          const std::array<int, 3>& la = lowest_[std::size_t(entries_[a].box)];
          for (std::size_t b = a + 1; b < end; ++b) {
            const std::array<int, 3>& lb = lowest_[std::size_t(entries_[b].box)];
            if (std::max(la[0], lb[0]) == i && std::max(la[1], lb[1]) == j &&
                std::max(la[2], lb[2]) == k)
              f(entries_[a].box, entries_[b].box);
          }
        }
      }
    });
  }

 private:
  // (k, box); a struct, not a std::pair, whose constructor would zero the lists serially.
  struct Entry {
    int k, box;
    bool operator<(const Entry& o) const { return k < o.k || (k == o.k && box < o.box); }
  };

  // The entries [from, to) of column i n[1] + j.
  std::pair<std::size_t, std::size_t> column_entries(std::size_t column) const {
    std::size_t slot = column;
    if (sparse_) {
      const auto at = std::lower_bound(occupied_.begin(), occupied_.end(), column);
      if (at == occupied_.end() || *at != column) return {0, 0};
      slot = std::size_t(at - occupied_.begin());
    }
    return {column_start_[slot], column_start_[slot + 1]};
  }
  void place_dense(const std::vector<Range>& ranges);
  void place_sparse(const std::vector<Range>& ranges);

  CellGrid grid_;
  std::vector<std::array<int, 3>> lowest_;  // per box: its range's lowest cube
  bool sparse_ = false;
  std::vector<std::size_t> occupied_;      // sparse: the occupied columns, ascending
  std::vector<std::size_t> column_start_;  // per column (sparse: occupied column), then the end
  // (Left unwritten when sized: placed in parallel.)
  Unwritten<Entry> entries_;  // per column, sorted
};

}  // namespace sdfcontour::detail
