// libFuzzer target: arbitrary bytes as a .npy file, read as sdfcontour contour reads its input.
// Any outcome but sdfcontour::Error (a crash, a hang, a sanitizer report, another exception) is
// a finding.
#include "memory_file.h"
#include "sdfcontour/io/npy.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The reader maps a file: give it one in memory.
  const MemoryFile file(data, size);
  if (!file.ok()) return 0;
  const std::string path = file.path();
  try {
    const auto mapped = sdfcontour::map_npy(path);
    // Refuse to interpret more than a small array: the fuzzer's inputs are small anyway.
    if (mapped->count <= (1u << 20)) {
      const sdfcontour::SdfInput input = sdfcontour::sdf_input_from_npy(mapped, {});
      if (const auto* grid = sdfcontour::grid_view_of(input))
        sdfcontour::require_sign_change(*grid);
    }
  } catch (const sdfcontour::Error&) {
  }
  return 0;
}
