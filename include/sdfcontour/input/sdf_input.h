// What `contour` takes: a grid of samples viewed in place, or scattered samples.
#pragma once

#include <memory>
#include <variant>

#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// A grid viewed in place (float32 or float64, never copied or widened), with whatever owns or
/// maps the memory the view reads.
struct GridInput {
  GridView view;
  std::shared_ptr<const void> storage;  ///< keeps view.data alive
  bool file_mapped = false;  ///< view.data lies in a read-only mapping of a file (map_npy)
};

/// Scattered samples: points (n x 3) and their values (n).
struct ScatteredInput {
  Samples samples;
  double spacing = 0;  ///< the samples' spacing when known (an OpenVDB voxel size); 0: estimated
};

using SdfInput = std::variant<GridInput, ScatteredInput>;

/// An input that owns `grid`.
SdfInput grid_input(Grid grid);

/// For a grid viewed in a read-only file mapping, drops the pages read so far from memory: they
/// are read from the file again when next used. Stages that have taken what they need from a grid
/// (the band's samples) call it before allocating more. Otherwise nothing.
void release_resident_pages(const SdfInput& input);

/// The input's grid view, or nullptr for scattered samples.
inline const GridView* grid_view_of(const SdfInput& input) {
  const GridInput* grid = std::get_if<GridInput>(&input);
  return grid ? &grid->view : nullptr;
}

}  // namespace sdfcontour
