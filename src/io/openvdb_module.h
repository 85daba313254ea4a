// Internal: OpenVDB behind a module loaded on first use. Linking libopenvdb into a program costs
// ~85 ms of symbol relocation at every start (twice for the CLI, which runs itself again for huge
// pages), more than marching cubes takes on a 256^3 grid; only .vdb input and output need it.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "sdfcontour/io/vdb.h"

namespace sdfcontour::detail {

/// How a module call ended; no exception crosses the module's boundary.
struct OpenVdbStatus {
  enum Kind { Ok, BadInput, Io, OutOfMemory, Internal } kind = Ok;
  std::string message;  ///< one line, for every kind but Ok
};

/// A grid to write: dims[0] x dims[1] x dims[2] values in C order, sample (i, j, k) at
/// origin + h (i, j, k).
struct OpenVdbGridToWrite {
  int dims[3];
  double h;
  double origin[3];
  const double* values;
  float background;  ///< > 0: voxels with |value| < background are active
  std::string name;
};

/// A level set's index space, for reading it box by box: the active voxels' bounding box, the
/// index-to-world map (uniform voxels: world = origin + voxel * ijk), and the origins of the
/// leaf nodes (8^3 voxels) that hold active voxels.
struct OpenVdbLayout {
  std::string grid_name;
  int min[3] = {0, 0, 0}, max[3] = {0, 0, 0};  ///< active voxels' bounding box, inclusive
  double voxel = 0, origin[3] = {0, 0, 0};
  /// The index axes' world directions, row a for index axis a (unit and orthogonal).
  double rotation[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double background = 0;
  std::vector<int> leaf_origins;  ///< 3 per leaf with active voxels
};

/// The module's entry points (the same compiler and standard library on both sides).
struct OpenVdbFunctions {
  /// Reads the float level set named grid_name (empty: the first float grid) into `out`.
  OpenVdbStatus (*read)(const std::string& path, const std::string& grid_name, VdbLevelSet& out);
  /// Writes the grid as a level set to `out`.
  OpenVdbStatus (*write)(const OpenVdbGridToWrite& grid, std::ostream& out);
  /// The level set's layout (topology and metadata only).
  OpenVdbStatus (*layout)(const std::string& path, const std::string& grid_name,
                          OpenVdbLayout& out);
  /// The values of voxels [first, first + dims) in C order (inactive ones as the signed
  /// background), reading only the part of the file that the box needs.
  OpenVdbStatus (*read_box)(const std::string& path, const std::string& grid_name,
                            const int first[3], const int dims[3], std::vector<float>& out);
};

/// The module's functions, loaded on first use (thread-safe). Throws IoError when the module
/// cannot be found or loaded, naming where it looked.
const OpenVdbFunctions& openvdb_functions();

}  // namespace sdfcontour::detail

/// The module's one exported symbol.
extern "C" const sdfcontour::detail::OpenVdbFunctions* sdfcontour_openvdb_functions();
