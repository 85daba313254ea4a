// libFuzzer target: arbitrary bytes as the replies of the child process that reads a .vdb file
// (src/io/vdb_replies.h). The child parses hostile files with OpenVDB, so its replies are
// untrusted too: a level set's points, and a layout with the grid and leaf boxes made from it.
// Any outcome but sdfcontour::Error (a crash, a sanitizer report, another exception) is a
// finding. In-process, so it runs far faster than fuzz_vdb, whose every input starts a child.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/vdb_replies.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const sdfcontour::VdbLevelSet s = sdfcontour::detail::parse_level_set_reply(bytes);
    sdfcontour::validate_samples(s.samples);
  } catch (const sdfcontour::Error&) {
  }
  try {
    const sdfcontour::VdbLayout layout = sdfcontour::detail::parse_layout_reply(bytes, "fuzz");
    const sdfcontour::BlockedGrid grid = sdfcontour::detail::blocked_grid_of(layout, "fuzz");
    sdfcontour::vdb_world_from_grid(layout);
    // Every leaf's box lies in the grid, a voxel's margin aside (the grid is the active voxels'
    // box grown by one; a leaf reaches 7 past it).
    for (const sdfcontour::SampleBox& box : *grid.surface_boxes)
      for (std::size_t a = 0; a < 3; ++a)
        if (box.lo[a] < -7 || box.hi[a] > grid.dims[a] + 7) __builtin_trap();
  } catch (const sdfcontour::Error&) {
  }
  return 0;
}
