// Contouring the zero level set directly: marching tetrahedra on a triangulation's cells and
// marching cubes on a grid. Inside is value < 0; a zero value counts as outside.
#pragma once

#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// Marching tetrahedra on `tets` (m x 4, positively oriented) over samples (`points` n x 3,
/// `values` n). Vertices sit on sign-changing edges by linear interpolation and are shared
/// between tets, so the mesh is closed and outward oriented wherever the surface stays inside
/// the triangulated region. Each quad is split along its shorter diagonal.
Mesh marching_tetrahedra(const PointMatrix& points, const Eigen::VectorXd& values,
                         const TetMatrix& tets);

/// Marching cubes on a grid. Each cube's polygons are traced around its faces; a face with two
/// diagonal pairs of equal sign is resolved by the asymptotic decider (the sign of the bilinear
/// interpolant's saddle), which both cubes sharing the face agree on, so there are no cracks.
/// The output is closed and outward oriented wherever the surface stays inside the grid.
/// Float32 grids are read as float32, and memory beyond the mesh is O(nx * ny).
Mesh marching_cubes(const GridView& grid);
Mesh marching_cubes(const Grid& grid);

}  // namespace sdfcontour
