// Internal: a brick's moves of its mesh (local_brick.cpp), each with bounded reach: onto the
// grid's zero set where its values are no distances, carving vertex by vertex and the samples'
// side rounds (the undoing of crossing moves is revert_self_intersections with a round limit).
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

/// The band of the samples whose balls carve a brick's mesh (auto_carving_band; 0: the band's
/// own, or no carving).
double carving_band(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// The samples whose balls carve a brick's mesh where they are more than the band's core: the
/// wider carving band's, from `block` (none where there is no wider band; empty where the block
/// has none).
std::optional<BandSamples> wider_carving_band(const GridView& block, const LocalBrickOptions& o);

/// `rounds` of moving the nearest feature of each band sample within a spacing `h` of the
/// surface that lies on the wrong side of `mesh` until it lies just on its own side.
/// With `near_vertices` (a flag per vertex), only the samples within 2 h of a flagged vertex.
void put_samples_on_their_sides(Mesh& mesh, const BandSamples& band, double h, int rounds,
                                const std::vector<char>* near_vertices = nullptr);

/// The vertices of `mesh` whose band samples are no distances to it (zero_set_refinement.h),
/// moved onto the tricubic zero set of `block`; `stay` (if given: empty, or one flag per
/// vertex) gains them. With `fallback` (one position per vertex, NaN for none), a vertex the
/// interpolant could not move tries again from there.
void refine_vertices_on_zero_set(const GridView& block, const BandSamples& band,
                                 const LocalBrickOptions& options, Mesh& mesh,
                                 const std::vector<char>* fixed, std::vector<char>* stay,
                                 const PointMatrix* fallback = nullptr);

}  // namespace sdfcontour::detail
