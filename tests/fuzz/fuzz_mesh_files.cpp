// libFuzzer target: arbitrary bytes through our PLY, OFF and OBJ readers, and what read_mesh and
// read_oriented_points then do with the result. Any exception other than Error is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/mesh_files.h"
#include "sdfcontour/types.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  using namespace sdfcontour::detail;
  for (auto parse : {&parse_ply, &parse_off, &parse_obj}) {
    try {
      const PolygonSoup soup = parse(bytes, "fuzz");
      // What the callers check next: indices in range, normals one per point.
      for (const auto& polygon : soup.polygons)
        for (long v : polygon)
          if (v >= 0 && v < long(soup.points.size())) (void)soup.points[std::size_t(v)][0];
      if (!soup.normals.empty() && soup.normals.size() != soup.points.size()) __builtin_trap();
    } catch (const sdfcontour::Error&) {
    }
  }
  return 0;
}
