// sdfcontour's entry points for C++: a triangle mesh from signed-distance samples, one call per
// kind of input (a grid in memory, a function, scattered samples, an OpenVDB level set).
//
//   #include <sdfcontour/sdfcontour.h>
//   sdfcontour::Mesh mesh = sdfcontour::contour_grid(values.data(), {nx, ny, nz}, bounds);
//
// Every option of the command line (the Poisson solver, the band, the gradients, statistics)
// goes through pipeline/pipeline.h's contour(); this header is the short road.
#pragma once

#include <array>
#include <functional>
#include <string>

#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// How contour_grid meshes a grid; the defaults are the command line's.
struct GridSettings {
  /// "gcp" (contact points, then the local reconstruction), "mc" (marching cubes), "mt-rt" or
  /// "mt-dt" (marching tetrahedra on the regular or Delaunay triangulation).
  std::string method = "gcp";
  /// Merge the mesh where the surface is flat to within this many grid spacings (0: keep it as
  /// reconstructed; 0.02 gives 5-47x fewer triangles at 256^3 within 1.1x the L1).
  double adaptivity = 0;
  /// Values at +-truncation carry no distance (a TSDF's clamp): < 0 detects it, 0 means none.
  double truncation = -1;
  /// Progress on stderr.
  bool progress = false;
};

/// Contours the `isovalue` level of a grid of signed distances (negative inside).
///
/// @param[in] values    nx*ny*nz samples in C order: values[(i*ny + j)*nz + k] is the sample at
///                      bounds.min + (i*hx, j*hy, k*hz), h = (bounds.max - bounds.min) / (n - 1);
///                      float or double, read in place, finite
/// @param[in] dims      (nx, ny, nz), each >= 2
/// @param[in] bounds    the positions of the first and last samples on each axis
/// @param[in] isovalue  the level to contour: values - isovalue are taken as the distances
/// @param[in] settings  the method and its few choices (GridSettings)
/// @return the mesh: vertices (#V x 3) and triangles (#F x 3), counter-clockwise seen from
///         outside, closed where the surface stays inside the grid
/// @throws Error for bad input (a wrong size, NaN, no surface crossing the grid, an unknown
///         method), with a one-line message
Mesh contour_grid(const float* values, const std::array<int, 3>& dims, const Bounds& bounds,
                  double isovalue = 0, const GridSettings& settings = {});
Mesh contour_grid(const double* values, const std::array<int, 3>& dims, const Bounds& bounds,
                  double isovalue = 0, const GridSettings& settings = {});

/// Contours the `isovalue` level of a function sampled on a grid: contour_grid on
/// f(bounds.min + (i*hx, j*hy, k*hz)) for every sample (evaluated in parallel, so `f` must be
/// safe to call from several threads).
///
/// @param[in] f         the signed distance (negative inside) at a point
/// @param[in] dims      (nx, ny, nz) samples, each >= 2
/// @param[in] bounds    the positions of the first and last samples on each axis
/// @param[in] isovalue  the level to contour
/// @param[in] settings  as contour_grid's
/// @return the mesh, as contour_grid's
/// @throws Error as contour_grid does, and for a non-finite value of f (naming the point)
Mesh contour_function(const std::function<double(const Eigen::Vector3d&)>& f,
                      const std::array<int, 3>& dims, const Bounds& bounds, double isovalue = 0,
                      const GridSettings& settings = {});

/// How contour_samples meshes scattered samples; the defaults are the command line's.
struct SampleSettings {
  /// "gcp" (contact points from the regular triangulation, then screened Poisson), "mt-rt" or
  /// "mt-dt" (marching tetrahedra on the regular or Delaunay triangulation).
  std::string method = "gcp";
  /// GCP's Poisson octree depth (1-14; 0: chosen from the samples' spacing).
  int depth = 0;
  /// Merge the mesh where the surface is flat to within this many sample spacings (0: none).
  double adaptivity = 0;
  /// Progress on stderr.
  bool progress = false;
};

/// Contours scattered samples of a signed distance (negative inside), as the paper does.
///
/// @param[in] points    #P x 3 sample positions, finite, not all on one plane
/// @param[in] values    #P signed distances at the points, finite
/// @param[in] settings  the method and its few choices (SampleSettings)
/// @return the mesh: vertices (#V x 3) and triangles (#F x 3), counter-clockwise seen from
///         outside
/// @throws Error for bad input (sizes that differ, NaN, too few samples, no sign change, an
///         unknown method), with a one-line message
Mesh contour_samples(const PointMatrix& points, const Eigen::VectorXd& values,
                     const SampleSettings& settings = {});

/// Contours the zero level set of a float grid in an OpenVDB file (a level set: negative
/// inside, its background the band's half width), read a block at a time for "gcp" and "mc"
/// (memory in proportion to its active voxels) and as scattered samples for "mt-rt"/"mt-dt".
/// The file's transform places the mesh (translations, scales and rotations).
///
/// @param[in] path       the .vdb file
/// @param[in] settings   as contour_grid's (truncation < 0: the grid's background)
/// @param[in] grid_name  the float grid to read; empty: the file's first
/// @return the mesh in world coordinates, as contour_grid's
/// @throws IoError for an unreadable file, Error for a file that holds no such level set
Mesh contour_vdb(const std::string& path, const GridSettings& settings = {},
                 const std::string& grid_name = "");

}  // namespace sdfcontour
