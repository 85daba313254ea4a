// The OpenVDB module (sdfcontour_openvdb.so): reads and writes float level sets for src/vdb.cpp,
// which loads it on first use (see openvdb_module.h). Self-contained: it uses none of
// libsdfcontour's symbols, and reports failures as statuses.
#include "openvdb_module.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <new>
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

void read_level_set(const std::string& path, const std::string& grid_name, VdbLevelSet& out) {
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    grids = file.getGrids();
    file.close();
  } catch (const std::bad_alloc&) {
    throw;  // reported as too much memory for the file
  } catch (const std::exception& e) {
    throw Failure{OpenVdbStatus::Io, "cannot read '" + path + "' as OpenVDB: " + e.what()};
  }
  openvdb::FloatGrid::Ptr grid;
  std::string names;
  for (const auto& g : *grids) {
    names += (names.empty() ? "" : ", ") + g->getName();
    auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!f) continue;
    if (grid_name.empty() ? !grid : g->getName() == grid_name) grid = f;
  }
  const std::string listed = " (grids: " + (names.empty() ? "none" : names) + ")";
  if (!grid && !grid_name.empty())
    throw Failure{OpenVdbStatus::BadInput,
                  "'" + path + "' has no float grid named '" + grid_name + "'" + listed};
  if (!grid) throw Failure{OpenVdbStatus::BadInput, "'" + path + "' has no float grid" + listed};
  if (grid->getGridClass() != openvdb::GRID_LEVEL_SET)
    throw Failure{OpenVdbStatus::BadInput,
                  "grid '" + grid->getName() + "' in '" + path +
                      "' is not a level set (its class is " +
                      openvdb::GridBase::gridClassToString(grid->getGridClass()) + ")"};
  const openvdb::math::Transform& xform = grid->transform();
  const openvdb::Vec3d voxel = xform.voxelSize();
  out.grid_name = grid->getName();
  out.voxel_size = std::max({voxel[0], voxel[1], voxel[2]});
  out.background = std::abs(double(grid->background()));
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

const OpenVdbFunctions kFunctions{&read, &write};

}  // namespace

}  // namespace sdfcontour::detail

extern "C" __attribute__((visibility("default"))) const sdfcontour::detail::OpenVdbFunctions*
sdfcontour_openvdb_functions() {
  return &sdfcontour::detail::kFunctions;
}
