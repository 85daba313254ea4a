// libFuzzer target: arbitrary bytes as a .vdb file, read as sdfcontour contour reads a level set
// (box by box, the default, and sparse, the Poisson path's) and as sdfcontour.dask reads one.
// Any outcome but sdfcontour::Error (a crash, a hang, a sanitizer report, another exception) is
// a finding. OpenVDB itself reads in a child process (src/io/isolated_call.h), whose failures the
// reader reports as IoError.
#include "memory_file.h"
#include "sdfcontour/io/vdb.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const MemoryFile file(data, size);
  if (!file.ok()) return 0;
  try {
    sdfcontour::read_vdb_level_set(file.path());
  } catch (const sdfcontour::Error&) {
  }
  try {  // the brick-by-brick readers (sdfcontour.dask): layout, then a box
    const sdfcontour::VdbLayout layout = sdfcontour::read_vdb_layout(file.path());
    sdfcontour::read_vdb_box(file.path(), "", layout.min, {4, 4, 4});
  } catch (const sdfcontour::Error&) {
  }
  try {  // the default path's grid: its placement, and the block of its first leaf
    sdfcontour::VdbLayout layout;
    const sdfcontour::BlockedGrid grid = sdfcontour::vdb_blocked_grid(file.path(), "", &layout);
    sdfcontour::vdb_world_from_grid(layout);
    if (grid.surface_boxes && !grid.surface_boxes->empty()) {
      std::array<int, 3> lo, hi;
      for (std::size_t a = 0; a < 3; ++a) {
        lo[a] = std::max(0, grid.surface_boxes->front().lo[a]);
        hi[a] = std::min(grid.dims[a], lo[a] + 4);
      }
      if (lo[0] < hi[0] && lo[1] < hi[1] && lo[2] < hi[2]) grid.read(lo, hi);
    }
  } catch (const sdfcontour::Error&) {
  }
  return 0;
}
