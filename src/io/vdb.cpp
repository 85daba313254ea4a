#include "sdfcontour/io/vdb.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <vector>

#include "io/atomic_file.h"
#include "io/file_checks.h"
#include "io/isolated_call.h"
#include "io/openvdb_module.h"
#include "io/vdb_replies.h"

namespace sdfcontour {

namespace {

// OpenVDB's reader is not meant for hostile bytes: refuse anything that does not start like a
// .vdb file (magic number 0x56444220, "VDB " little-endian) before handing it over.
void check_magic(const std::string& path) {
  require_readable_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot read '" + path + "': " + std::strerror(errno));
  unsigned char magic[8] = {};
  in.read(reinterpret_cast<char*>(magic), 8);
  const unsigned char expected[4] = {0x20, 0x42, 0x44, 0x56};
  if (in.gcount() < 8 || std::memcmp(magic, expected, 4) != 0)
    throw Error("'" + path + "' is not a .vdb file (bad magic number)");
}

}  // namespace

bool is_vdb_path(const std::string& path) {
  return path.size() >= 4 && path.compare(path.size() - 4, 4, ".vdb") == 0;
}

namespace {

// Throws the status's error, typed as the rest of the library types them.
void raise(const detail::OpenVdbStatus& status) {
  switch (status.kind) {
    case detail::OpenVdbStatus::Ok:
      return;
    case detail::OpenVdbStatus::BadInput:
      throw Error(status.message);
    case detail::OpenVdbStatus::Io:
      throw IoError(status.message);
    case detail::OpenVdbStatus::OutOfMemory:
      throw std::bad_alloc();
    case detail::OpenVdbStatus::Internal:
      break;
  }
  throw InternalError("OpenVDB: " + status.message);
}

// The reading child's limits: OpenVDB trusts its input (a 10 KB file can make it allocate
// gigabytes or read past its buffers), so it reads in a child process with bounded memory and
// time, and a hostile file ends as an error. The allowance is generous for real files: their
// voxels are stored at >= 2 bytes each, and a voxel costs ~100 bytes while read; `extra_bytes`
// is what the reply needs beyond that.
detail::IsolationLimits read_limits(const std::string& path, std::size_t extra_bytes) {
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  if (ec) throw IoError("cannot read '" + path + "': " + ec.message());
  detail::IsolationLimits limits;
  limits.memory_bytes =
      (std::size_t(1) << 30) + extra_bytes +
      std::size_t(std::min<std::uintmax_t>(file_size, std::uintmax_t(1) << 36)) * 64;
  limits.seconds = 5 + double(file_size) / 5e6;
  return limits;
}

// Reads the level set with OpenVDB (in the isolated child: see read_vdb_level_set).
VdbLevelSet read_with_openvdb(const std::string& path, const std::string& grid_name) {
  VdbLevelSet out;
  raise(detail::openvdb_functions().read(path, grid_name, out));
  return out;
}

}  // namespace

VdbLevelSet read_vdb_level_set(const std::string& path, const std::string& grid_name) {
  check_magic(path);
  detail::openvdb_functions();  // loaded here, so that the child only calls into it
  VdbLevelSet out = detail::parse_level_set_reply(detail::run_isolated(
      [&] { return detail::level_set_reply(read_with_openvdb(path, grid_name)); },
      "cannot read '" + path + "' as OpenVDB", read_limits(path, 0)));
  validate_samples(out.samples);
  return out;
}

VdbLayout read_vdb_layout(const std::string& path, const std::string& grid_name) {
  check_magic(path);
  detail::openvdb_functions();
  const std::string bytes = detail::run_isolated(
      [&] {
        detail::OpenVdbLayout l;
        raise(detail::openvdb_functions().layout(path, grid_name, l));
        return detail::layout_reply(l);
      },
      "cannot read '" + path + "' as OpenVDB", read_limits(path, 0));
  return detail::parse_layout_reply(bytes, path);
}

std::vector<float> read_vdb_box(const std::string& path, const std::string& grid_name,
                                const std::array<int, 3>& first, const std::array<int, 3>& dims) {
  check_magic(path);
  long double count = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1) throw Error("a box to read needs at least one voxel per axis");
    if ((long long)first[a] + dims[a] - 1 > std::numeric_limits<int>::max())
      throw Error("a box to read from a .vdb ends beyond OpenVDB's index range");
    count *= dims[a];
  }
  if (count > (1u << 30)) throw Error("a box to read from a .vdb holds at most 2^30 voxels");
  detail::openvdb_functions();
  const std::string bytes = detail::run_isolated(
      [&] {
        std::vector<float> values;
        raise(detail::openvdb_functions().read_box(path, grid_name, first.data(), dims.data(),
                                                   values));
        return std::string(reinterpret_cast<const char*>(values.data()),
                           values.size() * sizeof(float));
      },
      "cannot read '" + path + "' as OpenVDB", read_limits(path, std::size_t(count) * 4));
  if (bytes.size() != std::size_t(count) * sizeof(float))
    throw InternalError("the .vdb reader's reply has the wrong size");
  std::vector<float> values(static_cast<std::size_t>(count));
  std::memcpy(values.data(), bytes.data(), bytes.size());
  for (float v : values)
    if (!std::isfinite(v)) throw Error("'" + path + "' holds a non-finite value in the box read");
  return values;
}

BlockedGrid vdb_blocked_grid(const std::string& path, const std::string& grid_name,
                             VdbLayout* layout_out) {
  const VdbLayout layout = read_vdb_layout(path, grid_name);
  BlockedGrid grid = detail::blocked_grid_of(layout, path);
  if (layout_out) *layout_out = layout;
  return grid;
}

std::optional<Eigen::Affine3d> vdb_world_from_grid(const VdbLayout& layout) {
  if (layout.rotation == Eigen::Matrix3d::Identity()) return std::nullopt;
  Eigen::Affine3d placed = Eigen::Affine3d::Identity();
  placed.linear() = layout.rotation.transpose();
  placed.translation() = layout.origin;
  return placed;
}

void write_vdb_level_set(const std::string& path, const Grid& grid, double half_width,
                         const std::string& name) {
  const Eigen::Vector3d h = grid.spacing();
  if (std::abs(h[0] - h[1]) > 1e-9 * h[0] || std::abs(h[0] - h[2]) > 1e-9 * h[0])
    throw Error("a .vdb level set needs equal spacings on every axis (use cubic bounds)");
  if (!(half_width > 0)) throw Error("the level set's half width must be positive");
  const detail::OpenVdbFunctions& openvdb = detail::openvdb_functions();
  const detail::OpenVdbGridToWrite out{{grid.dims[0], grid.dims[1], grid.dims[2]},
                                       h[0],
                                       {grid.bounds.min[0], grid.bounds.min[1], grid.bounds.min[2]},
                                       grid.values.data(),
                                       float(half_width * h[0]),
                                       name};
  AtomicFile file(path);
  raise(openvdb.write(out, file.stream()));
  file.commit();
}

}  // namespace sdfcontour
