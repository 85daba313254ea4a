// Marching cubes one brick at a time: each brick of a larger grid gives the piece of the
// whole-grid mesh that it owns, with global vertex keys, so that pieces computed anywhere (other
// threads, processes or machines) join into exactly the mesh of marching_cubes(whole grid).
//
// Ownership: a brick owns the cells (cubes) whose eight samples it holds, and its block holds
// exactly the samples of the cells it owns: cells [first, first + block.dims - 1) on each axis.
// Bricks that partition the grid's cells therefore own every triangle exactly once. A vertex on
// a grid edge is named by the edge (key 3 * global index of its low sample + axis), so two
// bricks that share a face name its vertices alike and compute them from the same two values by
// the same formula: bit for bit the same position. A vertex added at a polygon's centroid (see
// marching.h) belongs to its cell alone: key 3 * N + 4 * global cell index + its rank in the cell
// (N: the grid's sample count).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sdfcontour/input/blocked_grid.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// The part of a mesh that one brick owns.
struct MeshPiece {
  PointMatrix vertices;             ///< v x 3 positions, in ascending key order
  std::vector<std::uint64_t> keys;  ///< v global vertex keys, ascending and distinct
  TriangleMatrix triangles;         ///< f x 3 indices into `vertices`, outward oriented
};

/// Marching cubes on one brick of `grid`. `block` holds the samples with global indices
/// [first, first + block.dims) on each axis (C order, float32 or float64; its bounds are not
/// used: positions come from `grid`, the whole grid's dims and bounds, and global indices).
/// Throws Error unless block.dims >= 2, 0 <= first, first + block.dims <= grid.dims, the values
/// are finite, and the grid's keys fit in 64 bits. A block of one sign gives an empty piece
/// (checked in the same pass over the values). The triangles are those that
/// marching_cubes(whole grid) makes in the block's cells, the vertex positions bit for bit the
/// same.
MeshPiece marching_cubes_brick(const GridView& block, const GridGeometry& grid,
                               const std::array<int, 3>& first);

/// Joins pieces into one mesh: vertices with equal keys become one (in ascending key order),
/// triangles follow in piece order. Throws InternalError if two pieces give one key two
/// positions.
Mesh join_mesh_pieces(const std::vector<MeshPiece>& pieces);

/// Marching cubes of a grid read a block at a time (a .vdb level set): its cells in bricks of
/// `brick` a side, in C order, each read with the next sample on its high sides; bricks that
/// cannot hold the surface (BlockedGrid::may_hold_surface) go unread. The same triangles and
/// vertex positions as marching_cubes of the whole grid, in the bricks' order.
Mesh marching_cubes(const BlockedGrid& grid, int brick);

}  // namespace sdfcontour
