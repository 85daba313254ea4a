// A grid that is read a block at a time and never held whole: an OpenVDB level set in its file
// (vdb_blocked_grid, io/vdb.h). GCP's local reconstruction runs on it brick by brick
// (local_mesh_in_bricks, reconstruction/local_brick.h).
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <vector>

#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// The grid's dims and bounds (GridGeometry; first and whole unused) and how to read it.
struct BlockedGrid : GridGeometry {
  /// The values of samples [lo, hi) (whole-grid indices, lo < hi <= dims on each axis), C order.
  std::function<std::vector<float>(const std::array<int, 3>& lo, const std::array<int, 3>& hi)>
      read;
  /// Whether samples [lo, hi) may hold the surface: false says that every sample there lies
  /// beyond the band of values that carry a distance (no sign change, no value within it), and
  /// such a block goes unread. Empty: any block may.
  std::function<bool(const std::array<int, 3>& lo, const std::array<int, 3>& hi)> may_hold_surface;
};

/// How many bricks of `side` partition [0, extent) on each axis (the last ones shorter).
inline long brick_count(const std::array<int, 3>& extent, int side) {
  long count = 1;
  for (int n : extent) count *= (long(n) + side - 1) / side;
  return count;
}

/// Calls visit(index, first, end) for each of those bricks, [first, end) on each axis, in C order
/// (index counts them from 0).
template <class Visit>
void for_each_brick(const std::array<int, 3>& extent, int side, Visit&& visit) {
  std::array<long, 3> count;
  for (std::size_t a = 0; a < 3; ++a) count[a] = (long(extent[a]) + side - 1) / side;
  for (long b = 0; b < count[0] * count[1] * count[2]; ++b) {
    const std::array<long, 3> at{b / (count[1] * count[2]), b / count[2] % count[1], b % count[2]};
    std::array<int, 3> first, end;
    for (std::size_t a = 0; a < 3; ++a) {
      first[a] = int(at[a]) * side;
      end[a] = std::min(first[a] + side, extent[a]);
    }
    visit(b, first, end);
  }
}

/// The block of samples [lo, hi) as a view (GridGeometry::first and ::whole set) of `values`,
/// which the grid's reader fills. Throws Error for a block outside the grid.
GridView read_block(const BlockedGrid& grid, const std::array<int, 3>& lo,
                    const std::array<int, 3>& hi, std::vector<float>& values);

}  // namespace sdfcontour
