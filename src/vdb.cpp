#include "sdfcontour/vdb.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>

#include "atomic_file.h"

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

VdbLevelSet read_vdb_level_set(const std::string& path, const std::string& grid_name) {
  initialise();
  check_magic(path);
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    grids = file.getGrids();
    file.close();
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
  const openvdb::Index64 count = grid->activeVoxelCount();
  if (count == 0)
    throw Error("grid '" + out.grid_name + "' in '" + path + "' has no active voxels");
  // Active tiles would stand for many voxels; a level set has none, and we do not densify them.
  if (grid->tree().activeTileCount() > 0)
    throw Error("grid '" + out.grid_name + "' has active tiles; a narrow-band level set has none");
  out.samples.points.resize(Eigen::Index(count), 3);
  out.samples.values.resize(Eigen::Index(count));
  Eigen::Index at = 0;
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    const openvdb::Vec3d p = xform.indexToWorld(it.getCoord());
    out.samples.points.row(at) = Eigen::RowVector3d(p[0], p[1], p[2]);
    out.samples.values[at++] = double(*it);
  }
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
