#include "pipeline/grid_source.h"

#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/metrics/field_agreement.h"

namespace sdfcontour::detail {

namespace {

bool dense_sides_inside(const GridView& grid) {
  const auto& n = grid.dims;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j) {
      const bool side_ij = i == 0 || j == 0 || i == n[0] - 1 || j == n[1] - 1;
      for (int k = 0; k < n[2]; k += side_ij ? 1 : n[2] - 1) {
        if (grid.value(grid.index(i, j, k)) < 0) return true;
        if (n[2] == 1) break;
      }
    }
  return false;
}

}  // namespace

const GridGeometry& GridSource::geometry() const {
  if (dense) return *dense;
  return *sparse;
}

BandSamples GridSource::select_band(const BandOptions& options) const {
  return dense ? sdfcontour::select_band(*dense, options)
               : sdfcontour::select_band(*sparse, options);
}

long GridSource::sign_change_edges() const {
  return dense ? sdfcontour::sign_change_edges(*dense) : sdfcontour::sign_change_edges(*sparse);
}

bool GridSource::sides_inside() const {
  return dense ? dense_sides_inside(*dense) : sdfcontour::sides_inside(*sparse);
}

double GridSource::fraction_off_zero_set(const Mesh& mesh, double tolerance, double scale) const {
  return dense ? sdfcontour::fraction_off_zero_set(*dense, mesh, tolerance, scale)
               : sdfcontour::fraction_off_zero_set(*sparse, mesh, tolerance, scale);
}

Mesh GridSource::marching_cubes() const {
  return dense ? sdfcontour::marching_cubes(*dense) : sdfcontour::marching_cubes(*sparse);
}

GridSource grid_source_of(const SdfInput& input) {
  GridSource source;
  source.dense = grid_view_of(input);
  if (const auto* sparse = std::get_if<SparseGridInput>(&input)) source.sparse = &sparse->grid;
  return source;
}

}  // namespace sdfcontour::detail
