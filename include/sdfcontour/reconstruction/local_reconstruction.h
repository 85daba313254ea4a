// GCP's local reconstruction: a mesh from a grid's signs and the contact points near each cell,
// with no global solve (dual contouring with the contact points as Hermite data).
//
// Topology comes from the samples' signs: each cell the surface crosses gets one vertex per
// polygon of its marching-cubes case (the asymptotic decider resolves ambiguous faces the same way
// in both cells that share them), and each grid edge with a sign change gets the quad of the four
// vertices around it. The mesh is the dual of the marching-cubes mesh, so it is closed and
// 2-manifold wherever that one is (the surface inside the grid). Geometry comes from the contact
// points: a vertex minimises the squared distances to the tangent planes of the contact points near
// its cell (a quadric error, solved with rank truncation), so that on a flat patch it stays at the
// points' centroid, on an edge it moves onto the edge and at a corner onto the corner.
#pragma once

#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

struct LocalReconstructionOptions {
  /// Contact points within the cell grown by this many spacings on each side feed its vertex.
  /// Measured on bunny at 32^3: 0 and 0.2 alike, 0.5 worse (its centroid leaves the cell); on a
  /// box, 0.2 puts the faces' vertices 10x closer than 0 (GCP's face points lie on cell sides).
  double reach = 0.2;
  /// Rank truncation of the quadric: a direction whose eigenvalue of sum(n n^T) is below this
  /// fraction of the largest is not solved for (the vertex keeps the points' centroid along it).
  /// Planes that meet at more than ~2 asin(sqrt(ratio)) (16 degrees for 0.02) make a feature.
  double feature_ratio = 0.02;
  /// Robust reweighting rounds: after each solve a point whose plane misses the vertex by r
  /// weighs 1 / (1 + (r / (robust_scale spacings))^2), so that a few points with bent normals
  /// (next to an edge, where the field is not linear) do not pull a vertex off the feature.
  int robust_rounds = 3;
  double robust_scale = 0.01;
  /// Cells with fewer contact points than this use their edge crossings instead (linear
  /// interpolation, with the grid's central-difference gradient as normal).
  int min_points = 1;
  /// A polygon with fewer points within `reach` gathers them within this many spacings and takes
  /// its vertex from them if their quadric is an edge or corner in the cell, else uses its edge
  /// crossings: on exactly degenerate data (an exact box, grid-aligned) the regular
  /// triangulation's tie-breaking can leave a whole edge's cells without a point while both
  /// faces' points lie 1.5 spacings off. 0: no second gathering.
  double empty_cell_reach = 2.0;
  /// A contact point from a sample |value| away weighs 1 / (1 + (|value| / (depth_scale
  /// spacings))^2): a far sample's gradient error moves its point |value| times as far. 0: every
  /// point weighs the same (also when no depths are given).
  double depth_scale = 0;
  /// A vertex on a smooth patch (not an edge or corner, where the interpolant itself cuts the
  /// feature) farther than this many spacings from the zero set of the cell's trilinear
  /// interpolant (|value| / |gradient| there) disagrees with the samples' own sign changes
  /// (contact points of a field that is only roughly a distance): the cell falls back to its edge
  /// crossings. 0: no check.
  double max_field_miss = 0.5;
  /// The cells are narrower than the contact points' spacing (the grid at twice the samples'
  /// resolution that looks for thin parts, LocalBrickOptions::thin_parts), so a smooth patch's
  /// few points put their centroid anywhere, often outside the cell: its vertex is then the
  /// mean of the cell's edge crossings moved onto the points' plane, or the minimum slid along
  /// the plane into the cell, and where the plane misses the cell, the cell takes its edge
  /// crossings (bunny at 64^3 on that grid, clamped instead: a quarter of the vertices, and 11x
  /// the crossing triangles after the projection). Else (a cell a spacing wide) the vertex
  /// stays at the minimum, clamped into the cell.
  bool narrow_cells = false;
  /// Each edge's polygon is fanned from a vertex of its own on the grid edge, where the surface
  /// crosses it, instead of split along a diagonal: every triangle then lies in one cell or two
  /// that share a face, so vertices inside their cells cannot make the mesh cross itself (Ju and
  /// Udeshi's argument, 2006), at about twice the triangles.
  bool edge_fans = false;
};

struct LocalReconstructionStats {
  long cells = 0;             ///< cells the surface crosses
  long vertices = 0;          ///< one per polygon of each such cell
  long split_cells = 0;       ///< cells with more than one polygon (a vertex each)
  long crossing_cells = 0;    ///< vertices placed from edge crossings (too few contact points)
  long feature_vertices = 0;  ///< vertices whose quadric had rank 2 or 3 (an edge or a corner)
  long clamped = 0;           ///< vertices whose quadric's minimiser left the cell, clamped to it
  long field_misses = 0;      ///< vertices off the cell's interpolated zero set (max_field_miss)
  long thin_points = 0;       ///< points of the finer grid put in a thin part (LocalBrickOptions)
};

/// The local reconstruction of the zero level set of `grid` (inside: value < 0) from contact
/// points `points` (k x 3) with unit outward `normals` (k x 3) of the same field. Returns a mesh
/// whose vertices each lie in their own cell, triangles counter-clockwise seen from outside.
/// `depths` (k, or empty) are the |value|s of the points' samples, for options.depth_scale.
/// The result depends only on the inputs, not on their row order or the thread count.
/// Throws Error for mismatched sizes or non-finite points or normals.
Mesh local_reconstruction(const GridView& grid, const PointMatrix& points,
                          const PointMatrix& normals,
                          const LocalReconstructionOptions& options = {},
                          LocalReconstructionStats* stats = nullptr,
                          const Eigen::VectorXd& depths = Eigen::VectorXd());

}  // namespace sdfcontour
