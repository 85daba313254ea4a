// Grid edges that a part thinner than a spacing may cross unseen: the local reconstruction's
// choice of thin parts on fine grids (pipeline.h, auto_thin_parts).
#pragma once

#include <array>
#include <cstdint>

#include "sdfcontour/input/blocked_grid.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// Counts over a grid's edges (pairs of samples next to each other on one axis).
struct SubspacingGaps {
  /// Edges whose two samples lie on one side with |v1| + |v2| below the edge's length, the field
  /// rising away from the edge at both ends by more than half a spacing (v0 and v3, the samples
  /// beyond): on an exact distance, a part of the other side thinner than the edge (a blade, a
  /// wing, a slot) or a feature of a spacing's radius lies across it, with no sign change to show.
  std::int64_t gaps = 0;
  std::int64_t crossings = 0;  ///< edges whose two samples' sides differ (value < 0: inside)
};

/// The counts over the edges of `grid` (a block of its whole grid: GridGeometry::first, whole)
/// whose lower sample's whole-grid index lies in [own_first, own_end): blocks that own disjoint
/// parts sum to the whole grid's counts. `value_scale` turns values into distances. Edges at the
/// whole grid's sides, without a sample beyond them, are no gaps. The block must hold one sample
/// before and two after the owned ones where the whole grid has them (throws Error otherwise).
/// Parallel; windowed over a file-mapped grid (GridView::drop_pages).
SubspacingGaps count_subspacing_gaps(const GridView& grid, std::array<int, 3> own_first,
                                     std::array<int, 3> own_end, double value_scale = 1.0);

/// The counts over the whole of `grid`.
SubspacingGaps count_subspacing_gaps(const GridView& grid, double value_scale = 1.0);

/// The counts over the whole of a grid read a block at a time: bricks of `brick` samples a side,
/// each read with the samples its edges need around it; bricks that cannot hold the surface
/// (BlockedGrid::may_hold_surface: no sign change, so no value within a spacing) go unread.
SubspacingGaps count_subspacing_gaps(const BlockedGrid& grid, double value_scale, int brick);

}  // namespace sdfcontour
