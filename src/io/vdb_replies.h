// Internal: the replies of the child process that reads a .vdb file with OpenVDB
// (src/io/isolated_call.h), as bytes and back. The child parses hostile files, so the parent
// takes its replies as untrusted too: every parse checks sizes and ranges before anything is
// built from them (tests/fuzz/fuzz_vdb_replies.cpp).
#pragma once

#include <array>
#include <string>

#include "io/openvdb_module.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/io/vdb.h"

namespace sdfcontour::detail {

/// Active voxels this close to the ends of OpenVDB's index range (int) are refused: the grid
/// around them (a voxel wider), its leaves and any box read within it then stay inside the range.
constexpr int kVdbIndexMargin = 16;

/// The level set as bytes: name length, name, voxel size, background, count, then the points
/// (row-major) and the values.
std::string level_set_reply(const VdbLevelSet& s);
/// Throws InternalError for bytes of the wrong length.
VdbLevelSet parse_level_set_reply(const std::string& bytes);

/// The layout as bytes: name length, name, min, max, voxel, origin, rotation, background, then
/// the count of leaf coordinates and the coordinates (3 per leaf).
std::string layout_reply(const OpenVdbLayout& l);
/// Throws InternalError for bytes of the wrong length or leaves outside the bounding box (which
/// OpenVDB never reports), and Error (naming `path`) for a layout that no grid can hold: an
/// empty or inverted bounding box, voxels within kVdbIndexMargin of the index range's ends, a
/// degenerate transform, a background that is not positive.
VdbLayout parse_layout_reply(const std::string& bytes, const std::string& path);

/// The grid of `layout` (vdb_blocked_grid's), reading its boxes from `path` when asked.
/// `layout`: as parse_layout_reply returns it, whose checks keep this grid's sums inside int.
BlockedGrid blocked_grid_of(const VdbLayout& layout, const std::string& path);

}  // namespace sdfcontour::detail
