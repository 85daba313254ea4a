// Internal: what a brick of the local reconstruction owns (local_brick.cpp): the grid edges whose
// low sample lies in its owned range, their triangles and vertices, its cells' counts and its
// samples' contact points; the pieces of disjoint owned ranges join into the whole grid's mesh.
#pragma once

#include <array>
#include <cstdint>

#include "reconstruction/local/keyed_local_mesh.h"
#include "reconstruction/local/lattice_subdivision.h"
#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

using Index3 = std::array<int, 3>;

/// Grid point `index` (C order) of a grid of `n` points (or cells).
Index3 grid_point_of(std::uint64_t index, const Index3& n);
/// The C-order index of grid point `p` of a grid of `n` points: grid_point_of's inverse.
std::uint64_t grid_index_of(const Index3& p, const Index3& n);
/// The global [i, j, k] of `band`'s sample `s` (a block's band: `source` in the block's C order).
Index3 global_sample(const GridGeometry& block, const BandSamples& band, std::size_t s);
/// The low sample (i, j, k) of the grid edge named `edge` (3 * sample index + axis) on a grid of
/// `n` samples.
Index3 edge_low_point(std::uint64_t edge, const Index3& n);

/// Whether `p` lies in [lo, hi) on every axis.
bool in_range(const Index3& p, const Index3& lo, const Index3& hi);

/// The triangles of the grid edges with low sample in [lo, hi), in the order of their names,
/// with their vertices; in `crossing_means` (one row per vertex) the vertices' crossing means
/// (KeyedLocalMesh; a segment vertex's own position).
KeyedTriangles triangles_of_edges(const KeyedLocalMesh& keyed, const Index3& n, const Index3& lo,
                                  const Index3& hi, PointMatrix& crossing_means);

/// The reconstruction's counts over the cells whose low corner lies in [own_first, own_end).
LocalReconstructionStats owned_cell_stats(const KeyedLocalMesh& keyed, const Index3& n,
                                          const Index3& own_first, const Index3& own_end);

/// Into `piece`: the contact points `cp` of the band samples whose global index lies in
/// [own_first, own_end), with those indices, ascending (the band keeps the grid's order).
void keep_owned_contact_points(const GridView& block, const BandSamples& band,
                               const ContactPoints& cp, const Index3& own_first,
                               const Index3& own_end, LocalPiece& piece);

/// Into `piece`: the owned triangles of the subdivided brick mesh `sub` on a grid of `n` samples
/// and their vertices (keys stay ascending).
void take_owned_part(const SubdividedMesh& sub, const Index3& n, const Index3& own_first,
                     const Index3& own_end, LocalPiece& piece);

}  // namespace sdfcontour::detail
