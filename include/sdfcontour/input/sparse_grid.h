// A regular grid held only where it may hold the surface, as OpenVDB holds a level set: a callable
// SDF sampled near its zero set (python/sdfcontour/_callable_bricks.py) is contoured from it
// without an n^3 array. Each operation here gives what the same operation gives on the dense
// grid whose samples outside the stored bricks are bounds of the same sign (as the callable
// sampler leaves them): the same counts, signs and mesh (trilinear_value and
// fraction_off_zero_set: metrics/field_agreement.h; select_band: band/band.h).
#pragma once

#include <array>
#include <vector>

#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// A grid (its dims and bounds in the GridGeometry part; first and whole unused) cut into cubic
/// bricks of `brick` cells: brick (a, b, c) holds the samples [brick * (a, b, c), + brick) on each
/// axis, the last brick of an axis also the grid's last sample. A stored brick keeps a block of
/// values: its samples and the next one on each high side (dims min(brick, n - 1 - first) + 1).
/// Every other brick is one signed value `fill` standing for all of its samples: their sign, and
/// a size no larger than any of theirs (a bound: the field has no zero in such a brick).
struct SparseGrid : GridGeometry {
  int brick = 32;
  std::array<int, 3> bricks{0, 0, 0};  ///< bricks per axis: ceil((n - 1) / brick)
  /// The stored blocks (first: the brick's first sample; whole: this grid's dims; bounds: its
  /// bounds; dims as above), any order.
  std::vector<GridView> blocks;
  std::vector<int> block_of;  ///< per brick in C order: its index in `blocks`, or -1
  std::vector<double> fill;   ///< per brick in C order: the value of a brick not stored

  /// The brick (C order over `bricks`) that owns sample (i, j, k).
  int brick_index(int i, int j, int k) const;
  /// The value of sample (i, j, k): its stored value, or its brick's fill.
  double value(int i, int j, int k) const;
};

/// The samples a stored block owns, from its first one: all but its high sides, unless those are
/// the grid's.
std::array<int, 3> owned_dims(const SparseGrid& grid, const GridView& block);

/// The number of bricks of `brick` cells along an axis of n samples.
int bricks_along(int n, int brick);

/// Throws Error unless the grid is consistent (dims >= 2, bounds ordered, brick >= 1, `fill` and
/// `block_of` one per brick, each block at its brick's place with its dims) and every stored value
/// and fill is finite (a NaN named by its (i, j, k)).
void validate_sparse_grid(const SparseGrid& grid);

/// Throws Error if the grid has no sign change (no surface: all >= 0 or all < 0).
void require_sign_change(const SparseGrid& grid);

/// The grid edges whose two samples have different signs (as sign_change_edges of the dense
/// grid): counted in the stored blocks (a brick not stored has no sign change, nor has an edge
/// from it, since its values bound the field's distance to the surface from below).
long sign_change_edges(const SparseGrid& grid);

/// Whether some sample on the grid's sides is inside (negative).
bool sides_inside(const SparseGrid& grid);

/// Marching cubes of the grid (marching_cubes of the dense grid: its stored blocks' pieces
/// joined; a brick not stored has no sign change).
Mesh marching_cubes(const SparseGrid& grid);

}  // namespace sdfcontour
