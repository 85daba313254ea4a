// Internal: where the local reconstruction puts a polygon's vertex, from the tangent planes of
// the contact points near its cell (dual contouring's quadric step).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <vector>

#include "reconstruction/local/cell_quadric.h"
#include "sdfcontour/reconstruction/local_reconstruction.h"

namespace sdfcontour::detail {

/// A box within a cell: its edge crossings' bounding box, within the cell shrunk by its margin.
struct CrossingsBox {
  Eigen::Vector3d lo, hi;
};

/// One polygon's vertex and how it was placed.
struct VertexResult {
  Eigen::Vector3d position;
  bool from_crossings = false, feature = false, clamped = false, field_miss = false;
  bool corner = false;  // at the point that samples around a corner share (shared_corner)
  std::optional<Eigen::Vector3d> corner_beyond;  // such a point, outside the cell
  // The minimiser moved into the cell along the directions the planes leave free, if it gets
  // there (the quadric's value unchanged).
  std::optional<Eigen::Vector3d> fitted;
  // Edge fans, where no minimiser lies in the cell: the box of the cell's edge crossings, where
  // the cell's own surface is, for within_crossings. Clamped straight, the vertex stays level
  // with the feature beyond the cell: right where the feature's face runs along the clamp (a
  // box's edge just outside), 0.11 h off where the cell holds only slivers of the faces (a
  // polyhedral torus at 384^3, a crease 0.07-0.16 h outside). (The repaired mesh keeps the
  // clamp: its sharp-edge distances would grow 1-3%.)
  std::optional<CrossingsBox> crossings_box;
};

/// A feature from fewer planes than this may be no feature: a point at a corner has a normal
/// anywhere in the corner's cone, and with one other plane it makes an edge that is not there.
constexpr std::size_t kFewFeaturePlanes = 3;

/// The vertex of a polygon in the cell [lo, hi] (h: the spacing) from `planes`, its contact
/// points' tangent planes, or from its grid edges' `crossings` where the planes are fewer than
/// options.min_points: the corner that samples share if they do, else the quadric's
/// rank-truncated robust minimiser, kept a thousandth of the cell inside it (for edge fans, with
/// `crossings_box` where no minimiser lies in the cell).
VertexResult place_vertex(const std::vector<TangentPlane>& planes,
                          const std::vector<TangentPlane>& crossings, const Eigen::Vector3d& lo,
                          const Eigen::Vector3d& hi, double h,
                          const LocalReconstructionOptions& options);

/// The least point within `box` (a VertexResult's crossings_box) of the quadric of `planes` (the
/// planes that vertex was placed from): the caller keeps it or the clamped vertex, whichever the
/// grid's values put nearer the surface. Solved only for the vertex kept: place_vertex may run
/// several times for one cell, and the solve tries 27 sets of the box's faces.
Eigen::Vector3d within_crossings(const std::vector<TangentPlane>& planes, const CrossingsBox& box,
                                 double h, const LocalReconstructionOptions& options);

/// A cell next to a corner whose own points are too few (the exact cube at 256^3: the samples
/// near its edges give the corner their contact points) gathers the corner's points from farther
/// and has its minimiser there, beyond the cell. Its vertex is then the least-squares point of the
/// other planes within the cell: on the edges that cross it. Measured (cube 256^3, TOL 0): the 24
/// such cells' vertices had taken their crossings, 0.1 h inside both faces.
/// `wide`: the planes gathered farther; `corner`: the point they share beyond the cell. Nothing
/// where too few of the other planes pass through that point (a mesh's small facets).
std::optional<VertexResult> corner_edge_vertex(const std::vector<TangentPlane>& wide,
                                               const Eigen::Vector3d& corner,
                                               const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                               double h, const LocalReconstructionOptions& options);

}  // namespace sdfcontour::detail
