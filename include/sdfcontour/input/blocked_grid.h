// A grid that is read a block at a time and never held whole: an OpenVDB level set in its file
// (vdb_blocked_grid, io/vdb.h). GCP's local reconstruction runs on it brick by brick
// (local_mesh_in_bricks, reconstruction/local_brick.h).
#pragma once

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

/// The block of samples [lo, hi) as a view (GridGeometry::first and ::whole set) of `values`,
/// which the grid's reader fills. Throws Error for a block outside the grid.
GridView read_block(const BlockedGrid& grid, const std::array<int, 3>& lo,
                    const std::array<int, 3>& hi, std::vector<float>& values);

}  // namespace sdfcontour
