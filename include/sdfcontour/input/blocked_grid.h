// A grid that is read a block at a time and never held whole: an OpenVDB level set in its file
// (vdb_blocked_grid, io/vdb.h). GCP's local reconstruction runs on it brick by brick
// (local_mesh_in_bricks, reconstruction/local_brick.h).
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <optional>
#include <vector>

#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// Samples [lo, hi) of a grid.
struct SampleBox {
  std::array<int, 3> lo, hi;
};

/// The grid's dims and bounds (GridGeometry; first and whole unused) and how to read it.
struct BlockedGrid : GridGeometry {
  /// The values of samples [lo, hi) (whole-grid indices, lo < hi <= dims on each axis), C order.
  std::function<std::vector<float>(const std::array<int, 3>& lo, const std::array<int, 3>& hi)>
      read;
  /// Whether samples [lo, hi) may hold the surface: false says that every sample there lies
  /// beyond the band of values that carry a distance (no sign change, no value within it), and
  /// such a block goes unread. Empty: any block may.
  std::function<bool(const std::array<int, 3>& lo, const std::array<int, 3>& hi)> may_hold_surface;
  /// Where known, boxes outside which no sample is near the surface (an OpenVDB level set's
  /// leaves: beyond them every value is the signed background). The brick drivers then visit
  /// only the bricks that meet one, at a cost in proportion to the boxes, not to the grid's
  /// extent (two spheres 1e5 voxels apart on a diagonal span 6e4 bricks of 256 per axis).
  std::optional<std::vector<SampleBox>> surface_boxes;
};

/// The C-order indices, ascending, of the bricks of `side` that partition [0, extent) (the last
/// ones shorter on each axis) whose samples, grown by `grow` on each side, meet one of `boxes`;
/// every brick where `boxes` is null.
std::vector<long> bricks_meeting(const std::array<int, 3>& extent, int side,
                                 const std::vector<SampleBox>* boxes, int grow);

/// The bricks of a blocked grid that its drivers visit, with their samples grown by `grow`:
/// bricks_meeting its surface boxes where it has them, else every brick.
inline std::vector<long> bricks_to_visit(const BlockedGrid& grid, const std::array<int, 3>& extent,
                                         int side, int grow) {
  return bricks_meeting(extent, side, grid.surface_boxes ? &*grid.surface_boxes : nullptr, grow);
}

/// Calls visit(position, first, end) for the bricks of `side` with C-order indices `bricks` (as
/// bricks_meeting gives them), position counting them from 0.
template <class Visit>
void for_each_listed_brick(const std::array<int, 3>& extent, int side,
                           const std::vector<long>& bricks, Visit&& visit) {
  std::array<long, 3> count;
  for (std::size_t a = 0; a < 3; ++a) count[a] = (long(extent[a]) + side - 1) / side;
  for (std::size_t n = 0; n < bricks.size(); ++n) {
    const long b = bricks[n];
    const std::array<long, 3> at{b / (count[1] * count[2]), b / count[2] % count[1], b % count[2]};
    std::array<int, 3> first, end;
    for (std::size_t a = 0; a < 3; ++a) {
      first[a] = int(at[a]) * side;
      end[a] = std::min(first[a] + side, extent[a]);
    }
    visit(long(n), first, end);
  }
}

/// The block of samples [lo, hi) as a view (GridGeometry::first and ::whole set) of `values`,
/// which the grid's reader fills. Throws Error for a block outside the grid.
GridView read_block(const BlockedGrid& grid, const std::array<int, 3>& lo,
                    const std::array<int, 3>& hi, std::vector<float>& values);

}  // namespace sdfcontour
