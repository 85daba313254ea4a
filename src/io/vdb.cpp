#include "sdfcontour/io/vdb.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <vector>

#include "io/atomic_file.h"
#include "io/file_checks.h"
#include "io/isolated_call.h"
#include "io/openvdb_module.h"

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

template <class T>
void put(std::string& out, const T* data, std::size_t count) {
  out.append(reinterpret_cast<const char*>(data), sizeof(T) * count);
}

template <class T>
void take(const std::string& bytes, std::size_t& at, T* data, std::size_t count) {
  if (count > (bytes.size() - at) / sizeof(T))
    throw InternalError("the .vdb reader's reply is cut short");
  std::memcpy(data, bytes.data() + at, sizeof(T) * count);
  at += sizeof(T) * count;
}

// Reads the level set with OpenVDB (in the isolated child: see read_vdb_level_set).
VdbLevelSet read_with_openvdb(const std::string& path, const std::string& grid_name) {
  VdbLevelSet out;
  raise(detail::openvdb_functions().read(path, grid_name, out));
  return out;
}

// The level set as bytes for the trip from the child: name length, name, voxel size, background,
// count, then the points (row-major) and the values.
std::string serialise(const VdbLevelSet& s) {
  const std::uint64_t name_size = s.grid_name.size(), n = std::uint64_t(s.samples.values.size());
  std::string out;
  put(out, &name_size, 1);
  put(out, s.grid_name.data(), name_size);
  put(out, &s.voxel_size, 1);
  put(out, &s.background, 1);
  put(out, &n, 1);
  put(out, s.samples.points.data(), 3 * n);
  put(out, s.samples.values.data(), n);
  return out;
}

VdbLevelSet deserialise(const std::string& bytes) {
  std::size_t at = 0;
  VdbLevelSet s;
  std::uint64_t name_size = 0, n = 0;
  take(bytes, at, &name_size, 1);
  if (name_size > bytes.size()) throw InternalError("the .vdb reader's reply is cut short");
  s.grid_name.resize(name_size);
  take(bytes, at, s.grid_name.data(), name_size);
  take(bytes, at, &s.voxel_size, 1);
  take(bytes, at, &s.background, 1);
  take(bytes, at, &n, 1);
  if (n > (bytes.size() - at) / 32 || (bytes.size() - at) != 32 * n)
    throw InternalError("the .vdb reader's reply has the wrong size");
  s.samples.points.resize(Eigen::Index(n), 3);
  s.samples.values.resize(Eigen::Index(n));
  take(bytes, at, s.samples.points.data(), 3 * n);
  take(bytes, at, s.samples.values.data(), n);
  return s;
}

}  // namespace

VdbLevelSet read_vdb_level_set(const std::string& path, const std::string& grid_name) {
  check_magic(path);
  detail::openvdb_functions();  // loaded here, so that the child only calls into it
  VdbLevelSet out = deserialise(
      detail::run_isolated([&] { return serialise(read_with_openvdb(path, grid_name)); },
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
        std::string out;
        const std::uint64_t name_size = l.grid_name.size(), leaves = l.leaf_origins.size();
        put(out, &name_size, 1);
        put(out, l.grid_name.data(), name_size);
        put(out, l.min, 3);
        put(out, l.max, 3);
        put(out, &l.voxel, 1);
        put(out, l.origin, 3);
        put(out, l.rotation, 9);
        put(out, &l.background, 1);
        put(out, &leaves, 1);
        put(out, l.leaf_origins.data(), leaves);
        return out;
      },
      "cannot read '" + path + "' as OpenVDB", read_limits(path, 0));
  VdbLayout l;
  std::size_t at = 0;
  std::uint64_t name_size = 0, leaves = 0;
  take(bytes, at, &name_size, 1);
  if (name_size > bytes.size()) throw InternalError("the .vdb reader's reply is cut short");
  l.grid_name.resize(name_size);
  take(bytes, at, l.grid_name.data(), name_size);
  take(bytes, at, l.min.data(), 3);
  take(bytes, at, l.max.data(), 3);
  take(bytes, at, &l.voxel_size, 1);
  take(bytes, at, l.origin.data(), 3);
  double rotation[9];
  take(bytes, at, rotation, 9);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) l.rotation(a, b) = rotation[3 * a + b];
  take(bytes, at, &l.background, 1);
  take(bytes, at, &leaves, 1);
  if (leaves % 3 != 0 || leaves > bytes.size()) throw InternalError("the .vdb reply is malformed");
  std::vector<int> origins(leaves);
  take(bytes, at, origins.data(), leaves);
  for (std::size_t i = 0; i < leaves; i += 3)
    l.leaf_origins.push_back({origins[i], origins[i + 1], origins[i + 2]});
  if (!(l.voxel_size > 0) || !std::isfinite(l.voxel_size) || !l.origin.allFinite() ||
      !l.rotation.allFinite())
    throw Error("grid '" + l.grid_name + "' in '" + path + "' has a degenerate transform");
  return l;
}

std::vector<float> read_vdb_box(const std::string& path, const std::string& grid_name,
                                const std::array<int, 3>& first, const std::array<int, 3>& dims) {
  check_magic(path);
  long double count = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1) throw Error("a box to read needs at least one voxel per axis");
    count *= dims[a];
  }
  if (count > (1u << 30)) throw Error("a box to read from a .vdb holds at most 2^30 voxels");
  detail::openvdb_functions();
  const std::string bytes = detail::run_isolated(
      [&] {
        std::vector<float> values;
        raise(detail::openvdb_functions().read_box(path, grid_name, first.data(), dims.data(),
                                                   values));
        std::string out;
        put(out, values.data(), values.size());
        return out;
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
  if (layout.leaf_origins.empty())
    throw Error("grid '" + layout.grid_name + "' in '" + path + "' has no active voxels");
  BlockedGrid grid;
  std::array<int, 3> first;
  // A rotated grid is contoured in its own frame, origin at voxel (0, 0, 0).
  const Eigen::Vector3d origin =
      vdb_world_from_grid(layout) ? Eigen::Vector3d::Zero() : layout.origin;
  for (int a = 0; a < 3; ++a) {
    first[a] = layout.min[a] - 1;
    const long long n = (long long)layout.max[a] - first[a] + 2;
    if (n > (1 << 30)) throw Error("the level set in '" + path + "' is too large a grid");
    grid.dims[a] = int(n);
    grid.bounds.min[a] = origin[a] + layout.voxel_size * first[a];
    grid.bounds.max[a] = origin[a] + layout.voxel_size * (first[a] + grid.dims[a] - 1);
  }
  const std::string name = layout.grid_name;
  grid.read = [path, name, first](const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    std::array<int, 3> at, dims;
    for (int a = 0; a < 3; ++a) at[a] = first[a] + lo[a], dims[a] = hi[a] - lo[a];
    return read_vdb_box(path, name, at, dims);
  };
  // The leaves (8^3 voxels) in grid indices: outside them every voxel is inactive, its value the
  // signed background (the band's half width), so no sign changes there.
  std::vector<SampleBox> leaves;
  for (const auto& o : layout.leaf_origins) {
    SampleBox box;
    for (std::size_t a = 0; a < 3; ++a) {
      box.lo[a] = o[a] - first[a];
      box.hi[a] = box.lo[a] + 8;
    }
    leaves.push_back(box);
  }
  grid.surface_boxes = std::move(leaves);
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
