// Internal: a grid of twice the resolution whose signs also show the parts thinner than a
// spacing that the samples straddle without a sign change (a wing, a blade), read from the
// contact points on their two sides, so that the local reconstruction's topology includes them.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "pipeline/uninitialised_allocator.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour::detail {

/// A block at twice the resolution (2 n - 1 samples per axis over the same bounds), owning its
/// values. Not copyable: `view` points into `values`.
struct RefinedGrid {
  Unwritten<double> values;  // (every one written: a zero fill first was a serial pass)
  GridView view;
  /// The points between the samples whose side the contact points decided: their global
  /// (i, j, k) on the finer grid, ascending.
  std::vector<std::array<int, 3>> thin_points;

  RefinedGrid() = default;
  RefinedGrid(const RefinedGrid&) = delete;
  RefinedGrid& operator=(const RefinedGrid&) = delete;
  RefinedGrid(RefinedGrid&&) = default;
  RefinedGrid& operator=(RefinedGrid&&) = default;
};

/// `block` (a grid or a block of one, GridGeometry::first and ::whole naming where it lies) at
/// twice its resolution. The block's samples keep their values; a point x between them takes
///  1. the mean of the samples it lies between (the trilinear interpolant there); within a
///     spacing of the surface the tricubic one (tricubic_value, where its stencil holds no value
///     at or beyond `truncation` in size), closer to a distance's zero set, and where the two
///     disagree on the side, the signed distance to the nearest contact point's tangent plane;
///     at a crease (two of the contact points within a spacing with normals more than a radian
///     apart), behind every one of their tangent planes (or in front of every one), the signed
///     distance to the plane it lies closest to, where the interpolants said the other side
///     (next to a box's edge, where the field kinks);
///  2. the side of a sample's ball (radius |value|, which holds no surface) that holds x;
///  3. the other side where the contact points within a spacing say that a thin part passes:
///     x within a quarter spacing of the slab between two tangent planes that face away from
///     each other (a sheet of the other side; toward each other: a thin gap), each point behind
///     the other's plane, and no plane with x farther than that in front of it. Such a point
///     gets -+h / 8 (a topology marker: its vertices come from the contact points); the quarter
///     spacing makes a sheet of any thickness hold a point. Not on the whole grid's sides.
///
/// points, normals: k x 3 contact points and unit outward normals (those within a spacing and a
/// half of the block's points decide them; the same result in any block that holds them).
/// value_scale: the values times it are distances (BandOptions::value_scale).
RefinedGrid refine_for_thin_parts(const GridView& block, const PointMatrix& points,
                                  const PointMatrix& normals, double value_scale,
                                  double truncation);

}  // namespace sdfcontour::detail
