#include "sdfcontour/vdb.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <vector>

#include "atomic_file.h"
#include "isolated_call.h"

namespace sdfcontour {

namespace {

void initialise() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// OpenVDB's reader is not meant for hostile bytes: refuse anything that does not start like a
// .vdb file (magic number 0x56444220, "VDB " little-endian) before handing it over.
void check_magic(const std::string& path) {
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

// Reads the level set with OpenVDB (in the isolated child: see read_vdb_level_set).
VdbLevelSet read_with_openvdb(const std::string& path, const std::string& grid_name) {
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    grids = file.getGrids();
    file.close();
  } catch (const std::bad_alloc&) {
    throw;  // reported as too much memory for the file
  } catch (const std::exception& e) {
    throw IoError("cannot read '" + path + "' as OpenVDB: " + e.what());
  }
  openvdb::FloatGrid::Ptr grid;
  std::string names;
  for (const auto& g : *grids) {
    names += (names.empty() ? "" : ", ") + g->getName();
    auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!f) continue;
    if (grid_name.empty() ? !grid : g->getName() == grid_name) grid = f;
  }
  if (!grid) {
    if (!grid_name.empty())
      throw Error("'" + path + "' has no float grid named '" + grid_name +
                  "' (grids: " + (names.empty() ? "none" : names) + ")");
    throw Error("'" + path + "' has no float grid (grids: " + (names.empty() ? "none" : names) +
                ")");
  }
  if (grid->getGridClass() != openvdb::GRID_LEVEL_SET)
    throw Error("grid '" + grid->getName() + "' in '" + path +
                "' is not a level set (its class is " +
                openvdb::GridBase::gridClassToString(grid->getGridClass()) + ")");
  const openvdb::math::Transform& xform = grid->transform();
  const openvdb::Vec3d voxel = xform.voxelSize();
  VdbLevelSet out;
  out.grid_name = grid->getName();
  out.voxel_size = std::max({voxel[0], voxel[1], voxel[2]});
  out.background = std::abs(double(grid->background()));
  if (!(out.voxel_size > 0) || !std::isfinite(out.voxel_size))
    throw Error("grid '" + out.grid_name + "' has a degenerate transform");
  // One sequential pass (the child has no thread pool): voxels, and no active tiles, which
  // would stand for many voxels (a level set has none, and we do not densify them).
  std::vector<openvdb::Vec3d> points;
  std::vector<double> values;
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue())
      throw Error("grid '" + out.grid_name +
                  "' has active tiles; a narrow-band level set has none");
    points.push_back(xform.indexToWorld(it.getCoord()));
    values.push_back(double(*it));
  }
  if (points.empty())
    throw Error("grid '" + out.grid_name + "' in '" + path + "' has no active voxels");
  out.samples.points.resize(Eigen::Index(points.size()), 3);
  out.samples.values.resize(Eigen::Index(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    out.samples.points.row(Eigen::Index(i)) =
        Eigen::RowVector3d(points[i][0], points[i][1], points[i][2]);
    out.samples.values[Eigen::Index(i)] = values[i];
  }
  return out;
}

// The level set as bytes for the trip from the child: name length, name, voxel size, background,
// count, then the points (row-major) and the values.
std::string serialise(const VdbLevelSet& s) {
  const std::uint64_t name_size = s.grid_name.size(), n = std::uint64_t(s.samples.values.size());
  std::string out;
  auto put = [&](const void* data, std::size_t size) {
    out.append(static_cast<const char*>(data), size);
  };
  put(&name_size, 8);
  put(s.grid_name.data(), name_size);
  put(&s.voxel_size, 8);
  put(&s.background, 8);
  put(&n, 8);
  put(s.samples.points.data(), 24 * n);
  put(s.samples.values.data(), 8 * n);
  return out;
}

VdbLevelSet deserialise(const std::string& bytes) {
  std::size_t at = 0;
  auto take = [&](void* data, std::size_t size) {
    if (size > bytes.size() - at) throw InternalError("the .vdb reader's reply is cut short");
    std::memcpy(data, bytes.data() + at, size);
    at += size;
  };
  VdbLevelSet s;
  std::uint64_t name_size = 0, n = 0;
  take(&name_size, 8);
  if (name_size > bytes.size()) throw InternalError("the .vdb reader's reply is cut short");
  s.grid_name.resize(name_size);
  take(s.grid_name.data(), name_size);
  take(&s.voxel_size, 8);
  take(&s.background, 8);
  take(&n, 8);
  if (n > (bytes.size() - at) / 32 || (bytes.size() - at) != 32 * n)
    throw InternalError("the .vdb reader's reply has the wrong size");
  s.samples.points.resize(Eigen::Index(n), 3);
  s.samples.values.resize(Eigen::Index(n));
  take(s.samples.points.data(), 24 * n);
  take(s.samples.values.data(), 8 * n);
  return s;
}

}  // namespace

VdbLevelSet read_vdb_level_set(const std::string& path, const std::string& grid_name) {
  initialise();
  check_magic(path);
  // OpenVDB trusts its input (a 10 KB file can make it allocate gigabytes or read past its
  // buffers), so it reads in a child process with bounded memory and time: a hostile file ends
  // as an error. The allowance is generous for real files: their voxels are stored at >= 2
  // bytes each, and a voxel costs ~100 bytes while read.
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  if (ec) throw IoError("cannot read '" + path + "': " + ec.message());
  detail::IsolationLimits limits;
  limits.memory_bytes = std::size_t(1) << 30;
  limits.memory_bytes +=
      std::size_t(std::min<std::uintmax_t>(file_size, std::uintmax_t(1) << 36)) * 64;
  limits.seconds = 5 + double(file_size) / 5e6;
  VdbLevelSet out = deserialise(
      detail::run_isolated([&] { return serialise(read_with_openvdb(path, grid_name)); },
                           "cannot read '" + path + "' as OpenVDB", limits));
  validate_samples(out.samples);
  return out;
}

void write_vdb_level_set(const std::string& path, const Grid& grid, double half_width,
                         const std::string& name) {
  initialise();
  const Eigen::Vector3d h = grid.spacing();
  if (std::abs(h[0] - h[1]) > 1e-9 * h[0] || std::abs(h[0] - h[2]) > 1e-9 * h[0])
    throw Error("a .vdb level set needs equal spacings on every axis (use cubic bounds)");
  if (!(half_width > 0)) throw Error("the level set's half width must be positive");
  const float background = float(half_width * h[0]);
  auto out = openvdb::FloatGrid::create(background);
  out->setName(name);
  out->setGridClass(openvdb::GRID_LEVEL_SET);
  auto xform = openvdb::math::Transform::createLinearTransform(h[0]);
  xform->postTranslate(openvdb::Vec3d(grid.bounds.min[0], grid.bounds.min[1], grid.bounds.min[2]));
  out->setTransform(xform);
  auto accessor = out->getAccessor();
  for (int i = 0; i < grid.dims[0]; ++i)
    for (int j = 0; j < grid.dims[1]; ++j)
      for (int k = 0; k < grid.dims[2]; ++k) {
        const float v = float(grid.values[Eigen::Index(grid.index(i, j, k))]);
        if (std::abs(v) < background) accessor.setValue(openvdb::Coord(i, j, k), v);
      }
  // Inside the band's inner side, the background is negative: mark it by flood filling.
  openvdb::tools::signedFloodFill(out->tree());
  AtomicFile file(path);
  openvdb::io::Stream(file.stream()).write(openvdb::GridCPtrVec{out});
  file.commit();
}

}  // namespace sdfcontour
