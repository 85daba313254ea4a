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
  /// Whether samples [lo, hi) may hold a sign change; false lets a brick go unread. Empty: any
  /// block may.
  std::function<bool(const std::array<int, 3>& lo, const std::array<int, 3>& hi)> may_hold_surface;
};

}  // namespace sdfcontour
