// What `contour` takes: a grid of samples viewed in place, or scattered samples.
#pragma once

#include <memory>
#include <variant>

#include "sdfcontour/samples.h"

namespace sdfcontour {

/// A grid viewed in place (float32 or float64, never copied or widened), with whatever owns or
/// maps the memory the view reads.
struct GridInput {
  GridView view;
  std::shared_ptr<const void> storage;  ///< keeps view.data alive
};

/// Scattered samples: points (n x 3) and their values (n).
struct ScatteredInput {
  Samples samples;
  double spacing = 0;  ///< the samples' spacing when known (an OpenVDB voxel size); 0: estimated
};

using SdfInput = std::variant<GridInput, ScatteredInput>;

/// An input that owns `grid`.
SdfInput grid_input(Grid grid);

/// The input's grid view, or nullptr for scattered samples.
inline const GridView* grid_view_of(const SdfInput& input) {
  const GridInput* grid = std::get_if<GridInput>(&input);
  return grid ? &grid->view : nullptr;
}

}  // namespace sdfcontour
