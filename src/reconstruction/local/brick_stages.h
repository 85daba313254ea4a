// Internal: the stages of one brick of the local reconstruction after its contact points
// (local_brick.cpp), each on plain data: the dual mesh around the owned edges, its vertices
// settled, the subdivided mesh on the contact points' fit, the moves of bounded reach, and the
// undoing of crossing moves.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "reconstruction/chord_offsets.h"
#include "reconstruction/local/lattice_subdivision.h"
#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

using Index3 = std::array<int, 3>;

inline Index3 shifted(const Index3& p, int by) {
  return {p[0] + by, p[1] + by, p[2] + by};
}

inline Index3 times(const Index3& p, int factor) {
  return {p[0] * factor, p[1] * factor, p[2] * factor};
}

/// The dual mesh's triangles of a brick's owned edges and the ring around them (their vertices'
/// normals need every triangle), on the block's grid or, with thin parts, on the grid at twice
/// its resolution (thin_parts.h).
struct BrickDual {
  KeyedTriangles near;
  PointMatrix crossing_means;              ///< per vertex of `near`: its cell's crossings' mean
  std::vector<std::uint64_t> split_cells;  ///< with edge fans: cells with more than one polygon
  GridGeometry cells;                      ///< the grid whose cells hold the vertices
  int scale = 1;                           ///< its spacings per block spacing
  Index3 cells_first{}, cells_end{};       ///< the owned range on it
};

/// The dual mesh on the cells around the owned edges; the owned cells' counts go to `piece`.
/// With thin parts, the options' reaches go in the finer grid's spacings; its values go when it
/// is made (the fans keep to its cells after that).
BrickDual brick_dual_mesh(const GridView& block, const BandSamples& band, const ContactPoints& cp,
                          const Eigen::VectorXd& depths, const Index3& own_first,
                          const Index3& own_end, const LocalBrickOptions& options,
                          LocalPiece& piece);

/// The dual mesh's vertices, before they are subdivided: onto the grid's zero set where the values
/// are no distances (the subdivision's then start near it, and so do the positions that the
/// untangling goes back to), and apart where the quadrics (at features) made two nearby cells'
/// triangles cross: those vertices go to their crossings' mean.
void settle_dual_vertices(const GridView& block, const BandSamples& band,
                          const LocalBrickOptions& options, BrickDual& dual);

/// The brick's mesh on the contact points' fit: the dual mesh's triangles subdivided, projected
/// and split where their chords sag.
struct BrickSurface {
  SubdividedMesh sub;
  PointMatrix reconstructed;  ///< per vertex: where the reconstruction put it (before any move)
  std::vector<char> corners;  ///< per vertex: a corner that the samples around it share
  std::vector<char> stay;     ///< per vertex: not carved (those the fit kept; empty: none)
  /// Per vertex: the chord offset the projection gave it where the surface is smooth at the
  /// spacing's scale (not with edge fans), which the carving leaves in place.
  ChordOffsets chords;

  /// Per vertex: left where the reconstruction put it by the fit (with keep_features every
  /// feature vertex, else the shared corners).
  const std::vector<char>& fixed(const LocalBrickOptions& options) const {
    return options.keep_features ? sub.on_feature : corners;
  }
};

/// The subdivided mesh (auto_subdivisions levels of `n`, the whole grid's size, or the options'),
/// its vertices projected onto the contact points' fit, and its sagging chords split.
BrickSurface surface_on_contact_points(const BrickDual& dual, const ContactPoints& cp,
                                       const Eigen::VectorXd& depths, double h, const Index3& n,
                                       const LocalBrickOptions& options);

/// The moves whose reach is bounded, after the fit: carving by the samples' balls (`wider`'s
/// where the carving band is wider than the band), the samples' side rounds, with edge fans each
/// vertex back into its region (`dual_keys`: the dual mesh's vertices' names), and the grid's box.
void settle_vertices(const GridGeometry& block_geometry, const BandSamples& band,
                     std::optional<BandSamples> wider, const LocalBrickOptions& options,
                     const std::vector<std::uint64_t>& dual_keys, const BrickDual& dual,
                     BrickSurface& surface);

/// Undoes the moves of the vertices whose triangles then cross another; the samples near them,
/// whose sides that may have lost, get one more side round, without a crossing.
void untangle_moves(const BandSamples& band, double h, const LocalBrickOptions& options,
                    BrickSurface& surface);

}  // namespace sdfcontour::detail
