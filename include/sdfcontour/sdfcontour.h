// sdfcontour's entry point for C++: a triangle mesh from a grid of signed-distance samples.
//
//   #include <sdfcontour/sdfcontour.h>
//   sdfcontour::Mesh mesh = sdfcontour::contour_grid(values.data(), {nx, ny, nz}, bounds);
//
// Everything else the library does (scattered samples, .vdb level sets, callables, the paper's
// Poisson path, every option) goes through pipeline/pipeline.h's contour(); this header is the
// short road for the common case.
#pragma once

#include <array>
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

}  // namespace sdfcontour
