// Internal: our own readers of PLY, OFF and OBJ bytes. Third-party readers crashed, read out of
// bounds or allocated without limit on hostile files (issue 14), so nothing here trusts a count:
// every count and list length is checked against the bytes that remain before anything is
// allocated, and every number must be finite. Fuzzed by tests/fuzz/fuzz_mesh_files.cpp.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace sdfcontour::detail {

/// What a mesh or point file holds: vertices, their normals (when the file has nx ny nz), and
/// polygons as vertex indices (not yet checked against the vertex count).
struct PolygonSoup {
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<double, 3>> normals;  ///< empty, or one per point
  std::vector<std::vector<long>> polygons;
};

/// Each throws Error("cannot parse NAME as a PLY file: REASON") and the like for malformed bytes.
PolygonSoup parse_ply(std::string_view bytes, const std::string& name);
PolygonSoup parse_off(std::string_view bytes, const std::string& name);
PolygonSoup parse_obj(std::string_view bytes, const std::string& name);

}  // namespace sdfcontour::detail
