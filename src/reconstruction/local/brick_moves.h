// Internal: a brick's moves of its mesh after the projection (local_brick.cpp), each with bounded
// reach: carving vertex by vertex, the samples' side rounds, and undoing moves that cross.
#pragma once

#include <array>
#include <vector>

#include "sdfcontour/band.h"
#include "sdfcontour/local_brick.h"

namespace sdfcontour::detail {

/// The spacings that carving's balls reach (a coarse grid with the automatic band: 16); 0: the
/// band's own.
double carving_band(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// The samples whose balls carve a brick's mesh: the band's own (not its margin), or the wider
/// carving band's, selected from `block`.
Samples carving_samples(const GridView& block, const BandSamples& band,
                        const LocalBrickOptions& options);

/// `rounds` of moving the nearest feature of each band sample within a spacing `h` of the
/// surface that lies on the wrong side of `mesh` until it lies just on its own side.
/// With `near_vertices` (a flag per vertex), only the samples within 2 h of a flagged vertex.
void put_samples_on_their_sides(Mesh& mesh, const BandSamples& band, double h, int rounds,
                                const std::vector<char>* near_vertices = nullptr);

/// `rounds` of moving back to `before` every moved vertex of a triangle that crosses another;
/// returns which vertices moved back.
std::vector<char> undo_crossing_moves(Mesh& mesh, const PointMatrix& before, int rounds);

}  // namespace sdfcontour::detail
