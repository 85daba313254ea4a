// The whole grid as the stages after the band ask for it: a dense view or a sparse grid (a
// sampled callable). Internal to the library.
#pragma once

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/sdf_input.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// Neither pointer set: scattered samples (no grid).
struct GridSource {
  const GridView* dense = nullptr;
  const SparseGrid* sparse = nullptr;

  explicit operator bool() const { return dense || sparse; }
  const GridGeometry& geometry() const;
  // The grid's samples in the band (select_band).
  BandSamples select_band(const BandOptions& options) const;
  long sign_change_edges() const;
  // Whether some sample on the grid's sides is inside (negative): the surface runs out of the
  // grid (or the grid lies inside it), so the far field is not all outside.
  bool sides_inside() const;
  double fraction_off_zero_set(const Mesh& mesh, double tolerance, double scale) const;
  Mesh marching_cubes() const;
};

GridSource grid_source_of(const SdfInput& input);

}  // namespace sdfcontour::detail
