// libFuzzer target: arbitrary bytes as a .vdb file, read as sdfcontour contour reads a level set
// and as sdfcontour.dask reads one box by box.
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
  return 0;
}
