// The OpenVDB module (sdfcontour_openvdb.so): reads and writes float level sets for src/io/vdb.cpp,
// which loads it on first use (see openvdb_module.h). Self-contained: it uses none of
// libsdfcontour's symbols, and reports failures as statuses.
#include "io/openvdb_module.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <new>
#include <sstream>
#include <vector>

namespace sdfcontour::detail {

namespace {

struct Failure {
  OpenVdbStatus::Kind kind;
  std::string message;
};

void initialise() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Runs `read` (OpenVDB reading `path`): what OpenVDB throws becomes an I/O failure; our own
// failures and running out of memory pass as they are.
template <class Read>
auto reading(const std::string& path, Read&& read) {
  try {
    return read();
  } catch (const Failure&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw;  // reported as too much memory for the file
  } catch (const std::exception& e) {
    throw Failure{OpenVdbStatus::Io, "cannot read '" + path + "' as OpenVDB: " + e.what()};
  }
}

// The float level set `grid_name` (empty: the first float grid) of `file` (at `path`): all of
// it, or (with `box`) the part within that box of voxels. Only the chosen grid is read. With
// delayed loading its voxels are read from `file` when asked for: keep it until then.
openvdb::FloatGrid::Ptr read_float_level_set(openvdb::io::File& file, const std::string& path,
                                             const std::string& grid_name, bool delay_load,
                                             const openvdb::CoordBBox* box) {
  return reading(path, [&] {
    file.open(delay_load);
    openvdb::GridBase::Ptr chosen;
    std::string names;
    const openvdb::GridPtrVecPtr metadata = file.readAllGridMetadata();  // alive for the loop
    for (const auto& g : *metadata) {
      names += (names.empty() ? "" : ", ") + g->getName();
      if (!g->isType<openvdb::FloatGrid>()) continue;
      if (grid_name.empty() ? !chosen : g->getName() == grid_name) chosen = g;
    }
    const std::string listed = " (grids: " + (names.empty() ? "none" : names) + ")";
    if (!chosen && !grid_name.empty())
      throw Failure{OpenVdbStatus::BadInput,
                    "'" + path + "' has no float grid named '" + grid_name + "'" + listed};
    if (!chosen)
      throw Failure{OpenVdbStatus::BadInput, "'" + path + "' has no float grid" + listed};
    if (chosen->getGridClass() != openvdb::GRID_LEVEL_SET)
      throw Failure{OpenVdbStatus::BadInput,
                    "grid '" + chosen->getName() + "' in '" + path +
                        "' is not a level set (its class is " +
                        openvdb::GridBase::gridClassToString(chosen->getGridClass()) + ")"};
    if (!box) return openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(chosen->getName()));
    // The box in world space, grown by half a voxel so that its voxels are all read.
    const openvdb::math::Transform& xform = chosen->transform();
    const openvdb::Vec3d lo = xform.indexToWorld(box->min().asVec3d() - openvdb::Vec3d(0.5));
    const openvdb::Vec3d hi = xform.indexToWorld(box->max().asVec3d() + openvdb::Vec3d(0.5));
    const openvdb::BBoxd world(openvdb::math::minComponent(lo, hi),
                               openvdb::math::maxComponent(lo, hi));
    return openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(chosen->getName(), world));
  });
}

// A level set's background is the positive half width of its band (outside); a zero or negative
// one would read the inactive voxels outside as inside.
std::string background_error(const openvdb::FloatGrid& grid) {
  std::ostringstream message;
  message << "grid '" << grid.getName() << "' has the background " << grid.background()
          << "; a level set's is its band's half width, a positive distance";
  return message.str();
}

void read_level_set(const std::string& path, const std::string& grid_name, VdbLevelSet& out) {
  openvdb::io::File file(path);
  const openvdb::FloatGrid::Ptr grid =
      read_float_level_set(file, path, grid_name, /*delay_load=*/false, nullptr);
  const openvdb::math::Transform& xform = grid->transform();
  const openvdb::Vec3d voxel = xform.voxelSize();
  out.grid_name = grid->getName();
  out.voxel_size = std::max({voxel[0], voxel[1], voxel[2]});
  out.background = double(grid->background());
  if (!(out.background > 0) || !std::isfinite(out.background))
    throw Failure{OpenVdbStatus::BadInput, background_error(*grid)};
  if (!(out.voxel_size > 0) || !std::isfinite(out.voxel_size))
    throw Failure{OpenVdbStatus::BadInput,
                  "grid '" + out.grid_name + "' has a degenerate transform"};
  // One sequential pass (the reading child has no thread pool): voxels, and no active tiles,
  // which would stand for many voxels (a level set has none, and we do not densify them).
  std::vector<openvdb::Vec3d> points;
  std::vector<double> values;
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue())
      throw Failure{
          OpenVdbStatus::BadInput,
          "grid '" + out.grid_name + "' has active tiles; a narrow-band level set has none"};
    points.push_back(xform.indexToWorld(it.getCoord()));
    values.push_back(double(*it));
  }
  if (points.empty())
    throw Failure{OpenVdbStatus::BadInput,
                  "grid '" + out.grid_name + "' in '" + path + "' has no active voxels"};
  out.samples.points.resize(Eigen::Index(points.size()), 3);
  out.samples.values.resize(Eigen::Index(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    out.samples.points.row(Eigen::Index(i)) =
        Eigen::RowVector3d(points[i][0], points[i][1], points[i][2]);
    out.samples.values[Eigen::Index(i)] = values[i];
  }
}

void read_layout(const std::string& path, const std::string& grid_name, OpenVdbLayout& out) {
  openvdb::io::File file(path);  // kept while the topology is read
  const openvdb::FloatGrid::Ptr grid =
      read_float_level_set(file, path, grid_name, /*delay_load=*/true, nullptr);
  const openvdb::math::Transform& xform = grid->transform();
  const openvdb::Vec3d voxel = xform.voxelSize();
  if (!xform.isLinear() || std::abs(voxel[0] - voxel[1]) > 1e-9 * voxel[0] ||
      std::abs(voxel[0] - voxel[2]) > 1e-9 * voxel[0])
    throw Failure{OpenVdbStatus::BadInput,
                  "grid '" + grid->getName() + "' does not have uniform voxels"};
  // The index axes in world space: a rotation (distances kept) is contoured in index space and
  // turned after; a shear or a mirror is refused.
  const openvdb::Vec3d zero = xform.indexToWorld(openvdb::Vec3d(0, 0, 0));
  openvdb::Vec3d axes[3];
  for (int a = 0; a < 3; ++a) {
    openvdb::Vec3d unit(0, 0, 0);
    unit[a] = 1;
    axes[a] = (xform.indexToWorld(unit) - zero) / voxel[0];
  }
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (std::abs(axes[a].dot(axes[b]) - (a == b ? 1 : 0)) > 1e-9)
        throw Failure{OpenVdbStatus::BadInput,
                      "grid '" + grid->getName() + "' has a transform that shears its voxels"};
  if (axes[0].cross(axes[1]).dot(axes[2]) < 0)
    throw Failure{OpenVdbStatus::BadInput, "grid '" + grid->getName() +
                                               "' has a mirrored transform (its index axes are "
                                               "left-handed); mirror the mesh instead"};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out.rotation[3 * a + b] = axes[a][b];
  const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
  if (box.empty())
    throw Failure{OpenVdbStatus::BadInput, "grid '" + grid->getName() + "' has no active voxels"};
  out.grid_name = grid->getName();
  for (int a = 0; a < 3; ++a) out.min[a] = box.min()[a], out.max[a] = box.max()[a];
  out.voxel = voxel[0];
  for (int a = 0; a < 3; ++a) out.origin[a] = zero[a];
  out.background = double(grid->background());
  if (!(out.background > 0) || !std::isfinite(out.background))
    throw Failure{OpenVdbStatus::BadInput, background_error(*grid)};
  for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf)
    if (leaf->onVoxelCount() > 0)
      for (int a = 0; a < 3; ++a) out.leaf_origins.push_back(leaf->origin()[a]);
}

void read_box_values(const std::string& path, const std::string& grid_name, const int first[3],
                     const int dims[3], std::vector<float>& out) {
  const openvdb::CoordBBox box(
      openvdb::Coord(first[0], first[1], first[2]),
      openvdb::Coord(first[0] + dims[0] - 1, first[1] + dims[1] - 1, first[2] + dims[2] - 1));
  openvdb::io::File file(path);  // kept while the values are read
  const openvdb::FloatGrid::Ptr grid =
      read_float_level_set(file, path, grid_name, /*delay_load=*/true, &box);
  auto accessor = grid->getConstUnsafeAccessor();  // unregistered: no shared registry
  out.resize(std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]));
  std::size_t at = 0;
  for (int i = 0; i < dims[0]; ++i)
    for (int j = 0; j < dims[1]; ++j)
      for (int k = 0; k < dims[2]; ++k)
        out[at++] = accessor.getValue(openvdb::Coord(first[0] + i, first[1] + j, first[2] + k));
}

void write_level_set(const OpenVdbGridToWrite& in, std::ostream& stream) {
  auto out = openvdb::FloatGrid::create(in.background);
  out->setName(in.name);
  out->setGridClass(openvdb::GRID_LEVEL_SET);
  auto xform = openvdb::math::Transform::createLinearTransform(in.h);
  xform->postTranslate(openvdb::Vec3d(in.origin[0], in.origin[1], in.origin[2]));
  out->setTransform(xform);
  auto accessor = out->getAccessor();
  const double* value = in.values;
  for (int i = 0; i < in.dims[0]; ++i)
    for (int j = 0; j < in.dims[1]; ++j)
      for (int k = 0; k < in.dims[2]; ++k, ++value) {
        const float v = float(*value);
        if (std::abs(v) < in.background) accessor.setValue(openvdb::Coord(i, j, k), v);
      }
  // Inside the band's inner side, the background is negative: mark it by flood filling.
  openvdb::tools::signedFloodFill(out->tree());
  openvdb::io::Stream(stream).write(openvdb::GridCPtrVec{out});
  if (!stream) throw Failure{OpenVdbStatus::Io, "writing the level set failed"};
}

// Runs `work`, turning what it throws into a status.
template <class Work>
OpenVdbStatus guarded(Work&& work) {
  try {
    initialise();
    work();
    return {};
  } catch (const Failure& f) {
    return {f.kind, f.message};
  } catch (const std::bad_alloc&) {
    return {OpenVdbStatus::OutOfMemory, "out of memory"};
  } catch (const std::exception& e) {
    return {OpenVdbStatus::Internal, e.what()};
  } catch (...) {
    return {OpenVdbStatus::Internal, "unknown failure in the OpenVDB module"};
  }
}

OpenVdbStatus read(const std::string& path, const std::string& grid_name, VdbLevelSet& out) {
  return guarded([&] { read_level_set(path, grid_name, out); });
}

OpenVdbStatus write(const OpenVdbGridToWrite& grid, std::ostream& out) {
  return guarded([&] { write_level_set(grid, out); });
}

OpenVdbStatus layout(const std::string& path, const std::string& grid_name, OpenVdbLayout& out) {
  return guarded([&] { read_layout(path, grid_name, out); });
}

OpenVdbStatus read_box(const std::string& path, const std::string& grid_name, const int first[3],
                       const int dims[3], std::vector<float>& out) {
  return guarded([&] { read_box_values(path, grid_name, first, dims, out); });
}

const OpenVdbFunctions kFunctions{&read, &write, &layout, &read_box};

}  // namespace

}  // namespace sdfcontour::detail

extern "C" __attribute__((visibility("default"))) const sdfcontour::detail::OpenVdbFunctions*
sdfcontour_openvdb_functions() {
  return &sdfcontour::detail::kFunctions;
}
