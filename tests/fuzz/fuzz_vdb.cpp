// libFuzzer target: arbitrary bytes as a .vdb file, read as sdfcontour contour reads a level set.
// Any outcome but sdfcontour::Error (a crash, a hang, a sanitizer report, another exception) is
// a finding.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include "sdfcontour/vdb.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const int fd = ::memfd_create("fuzz.vdb", 0);
  if (fd < 0) return 0;
  if (size > 0 && ::write(fd, data, size) != ssize_t(size)) {
    ::close(fd);
    return 0;
  }
  try {
    sdfcontour::read_vdb_level_set("/proc/self/fd/" + std::to_string(fd));
  } catch (const sdfcontour::Error&) {
  }
  ::close(fd);
  return 0;
}
