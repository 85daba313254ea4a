// Whether a mesh agrees with the grid it was reconstructed from: its vertices should lie on the
// field's zero set, up to the reconstruction's error (well under a spacing for a distance).
#pragma once

#include "sdfcontour/input/samples.h"
#include "sdfcontour/input/sparse_grid.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// The field's trilinear interpolant at p (3), clamped to the grid's box.
double trilinear_value(const GridView& grid, const Eigen::Vector3d& p);
double trilinear_value(const SparseGrid& grid, const Eigen::Vector3d& p);

/// The fraction of `mesh`'s vertices where |scale * trilinear value| exceeds `tolerance` (world
/// units): 0 for a mesh on the zero set, near 1 for one that is not. 0 for a mesh with no
/// vertices.
double fraction_off_zero_set(const GridView& grid, const Mesh& mesh, double tolerance,
                             double scale = 1.0);
/// The same on a sparse grid: equal to the dense grid's count wherever the vertices' cells lie in
/// its stored bricks (elsewhere both grids hold bounds over the threshold they were sampled to).
double fraction_off_zero_set(const SparseGrid& grid, const Mesh& mesh, double tolerance,
                             double scale = 1.0);

}  // namespace sdfcontour
