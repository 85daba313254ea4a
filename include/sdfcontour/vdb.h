// OpenVDB level sets in and out. A level set is read sparse: its active voxels become scattered
// samples at their world positions, never a dense grid. Its background (the narrow band's half
// width) is the truncation distance: the outermost spacing inside it closes the stars of the
// samples that give contact points.
#pragma once

#include <string>

#include "sdfcontour/samples.h"

namespace sdfcontour {

/// True if `path` ends in ".vdb".
bool is_vdb_path(const std::string& path);

/// A float level set's active voxels.
struct VdbLevelSet {
  Samples samples;        ///< active voxels: world positions and values
  double voxel_size = 0;  ///< the largest voxel side, in world units
  double background = 0;  ///< the outside background value (the band's half width)
  std::string grid_name;  ///< the grid read
};

/// Reads the float level set named `grid_name` (empty: the first float grid) from a .vdb file.
/// Throws Error for an unreadable file, a file without a float grid, a named grid that is not
/// there, a grid that is not a level set, or one without active voxels.
VdbLevelSet read_vdb_level_set(const std::string& path, const std::string& grid_name = "");

/// Writes `grid` as a float level set named `name`: voxels with |value| < half_width * h are
/// active, the rest is background (+-half_width * h); the transform maps voxel (i,j,k) to the
/// grid's sample (i,j,k). Needs equal spacings on the three axes. Written atomically.
void write_vdb_level_set(const std::string& path, const Grid& grid, double half_width,
                         const std::string& name = "surface");

}  // namespace sdfcontour
