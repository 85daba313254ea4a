// libFuzzer target: arbitrary bytes as a .npy file, read as sdfcontour contour reads its input.
// Any outcome but sdfcontour::Error (a crash, a hang, a sanitizer report, another exception) is
// a finding.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include "sdfcontour/npy.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The reader maps a file: give it one in memory.
  const int fd = ::memfd_create("fuzz.npy", 0);
  if (fd < 0) return 0;
  if (size > 0 && ::write(fd, data, size) != ssize_t(size)) {
    ::close(fd);
    return 0;
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
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
  ::close(fd);
  return 0;
}
