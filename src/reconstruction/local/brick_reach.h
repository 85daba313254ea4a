// Internal: how far a brick of the local reconstruction reads beyond its owned samples
// (local_brick.cpp), from the options and the whole grid's size alone: the same for every brick.
#pragma once

#include <array>

#include "sdfcontour/band/band.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

/// The band's options with its auto band (0) resolved for the whole grid of `dims` (and the
/// contact points that the bricks make there).
BandOptions resolved_band(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// The largest |value| a band sample can have, in spacings. With every sample (band 'all') no
/// sphere reaches farther than the grid's diagonal matters.
double largest_in_spacings(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// Grid edges beyond the owned ones whose triangles a brick computes: their vertices' normals
/// need one ring; undoing crossings needs kUntangleRing (the dual mesh's rounds alone, fewer).
int edge_ring(const LocalBrickOptions& options);

/// How far beyond the owned samples a contact point can matter, in samples: the reach of the
/// ring of cells around the owned edges' cells (2), of a vertex's gathering or projection, and
/// of a sample to its contact point (its |value|, at most `largest` spacings).
int flag_reach(const LocalBrickOptions& options, double largest, const std::array<int, 3>& dims);

}  // namespace sdfcontour::detail
