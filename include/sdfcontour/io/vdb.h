// OpenVDB level sets in and out. A level set is read sparse: its active voxels become scattered
// samples at their world positions, never a dense grid. Its background (the narrow band's half
// width) is the truncation distance: the outermost spacing inside it closes the stars of the
// samples that give contact points.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sdfcontour/input/blocked_grid.h"
#include "sdfcontour/input/samples.h"

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

/// A level set's index space, for reading it brick by brick (never densified whole).
struct VdbLayout {
  std::string grid_name;
  std::array<int, 3> min{0, 0, 0}, max{0, 0, 0};     ///< active voxels' bounding box, inclusive
  double voxel_size = 0;                             ///< uniform voxel side, in world units
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< world position of voxel (0, 0, 0)
  /// Row a: the world direction of index axis a (a rotation; shears and mirrors are refused):
  /// voxel (i, j, k) lies at origin + voxel_size * rotation^T * (i, j, k).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  double background = 0;                         ///< the band's half width (outside value)
  std::vector<std::array<int, 3>> leaf_origins;  ///< leaves (8^3 voxels) with active voxels
};

/// The layout of the float level set `grid_name` (empty: the first) in a .vdb file, from its
/// topology. Throws Error as read_vdb_level_set does, and for non-uniform voxels.
VdbLayout read_vdb_layout(const std::string& path, const std::string& grid_name = "");

/// The values of the voxels [first, first + dims) (index space, C order; inactive voxels hold
/// the signed background), read from the part of the file that the box needs.
std::vector<float> read_vdb_box(const std::string& path, const std::string& grid_name,
                                const std::array<int, 3>& first, const std::array<int, 3>& dims);

/// The level set as a grid read box by box, never densified whole (as sdfcontour.dask reads it):
/// the active voxels' bounding box grown by one voxel, its samples at the voxels' world
/// positions (for a rotated transform, at voxel_size * (i, j, k): vdb_world_from_grid places
/// them); a block is read from the part of the file it needs (inactive voxels hold the signed
/// background), and a block that meets no leaf with active voxels cannot hold the surface.
/// `layout` (optional) gets the file's layout (the background is the band's half width).
BlockedGrid vdb_blocked_grid(const std::string& path, const std::string& grid_name = "",
                             VdbLayout* layout = nullptr);

/// Where vdb_blocked_grid's grid lies in the world: none for an axis-aligned transform (its
/// samples are at their world positions), else the rotation and origin of the layout.
std::optional<Eigen::Affine3d> vdb_world_from_grid(const VdbLayout& layout);

/// Writes `grid` as a float level set named `name`: voxels with |value| < half_width * h are
/// active, the rest is background (+-half_width * h); the transform maps voxel (i,j,k) to the
/// grid's sample (i,j,k). Needs equal spacings on the three axes. Written atomically.
void write_vdb_level_set(const std::string& path, const Grid& grid, double half_width,
                         const std::string& name = "surface");

}  // namespace sdfcontour
