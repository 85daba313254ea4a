// Compact meshes: a reconstruction's mesh merged where the contact points say the surface is
// flat enough, keeping creases and corners (their planes keep the merged vertex on them).
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour {

struct AdaptivityOptions {
  /// In spacings: a merge stands while the squared distances from the merged vertex to the
  /// tangent planes its region gathered (its contact points', and its triangles' own planes
  /// weighed by area over spacing^2), summed, stay under tolerance^2; 0 leaves the mesh as it is.
  double tolerance = 0;
  /// The merging runs brick by brick, in parallel: cubes of this many spacings from the mesh's
  /// lowest corner, then again on the bricks shifted by half a brick, so that every seam of the
  /// first pass lies inside a brick of the second. 0: the whole mesh as one brick (sequential).
  /// kAutoBricks: 32 where the mesh spans at most 64 spacings (a grid of up to 65 samples per
  /// axis, which bricks of 64 leave whole, on one core), else 64 (at 256^3 bricks of 32 keep up
  /// to 12% more triangles; docs/adaptivity.md).
  int brick_spacings = kAutoBricks;
  static constexpr int kAutoBricks = -1;
  /// A merge turns no triangle's normal by more than this many degrees (nor flips one).
  double max_normal_turn = 45;
  /// Rounds of the last step, a least-squares fit that moves the merged vertices so that their
  /// triangles pass through the unmerged mesh's vertices (which lie on the surface) instead of
  /// cutting chords under it; 0: the vertices stay at their quadrics' minima.
  int fit_rounds = 6;
};

struct AdaptivityStats {
  long triangles_before = 0;
  long triangles_after = 0;
  long merges = 0;           ///< edges collapsed (in the last round)
  int freeze_rounds = 0;     ///< rounds merged again with the vertices around crossings frozen
  long fitted_vertices = 0;  ///< vertices the fit moved (and kept: no move that crosses stays)
};

/// `mesh` (closed, 2-manifold, oriented) with its edges collapsed, cheapest first, while the
/// summed squared distance of the merged vertex to the tangent planes of the points (n x 3) with
/// unit `normals` (n x 3) that its region gathered stays under (options.tolerance spacings)^2:
/// each point joins the quadric of its nearest vertex, each vertex also holds its triangles'
/// planes, weighed by area over spacing^2 (a point stands for about h^2 of surface). The merged
/// vertex minimises the summed
/// quadric, with the directions the planes leave free kept at the edge's midpoint, so two planes
/// keep a crease and three a corner. Merges keep the mesh closed and 2-manifold (the link
/// condition) and turn no triangle by more than options.max_normal_turn. Where the merged mesh
/// crosses itself, it is merged again from `mesh` with the vertices within 3 spacings of the
/// crossing triangles frozen (up to 4 rounds; the regions of the input's own crossings are frozen
/// from the start): no merge adds a crossing unless 4 rounds do not suffice. A vertex on which
/// three or more points lie with normals that span every direction (a corner that samples on its
/// sides share) keeps its place in every merge, and no merge joins two. Then the merged
/// vertices, but those frozen and those corners, move so that the merged triangles fit the
/// input's vertices in the
/// least squares (options.fit_rounds; by at most a quarter spacing; moves that make triangles
/// cross are undone). Brick by brick
/// (options.brick_spacings): a vertex merges within its brick while its neighbours lie in it too;
/// the bricks run in parallel and are joined in order: the same mesh for any thread count.
/// Throws Error for mismatched sizes, a spacing that is not positive, a tolerance outside
/// [0, 10], a negative brick size (but kAutoBricks) or fit rounds outside [0, 100].
Mesh adapt_mesh(const Mesh& mesh, const PointMatrix& points, const PointMatrix& normals,
                double spacing, const AdaptivityOptions& options, AdaptivityStats* stats = nullptr);

}  // namespace sdfcontour
