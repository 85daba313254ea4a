// What `contour` takes: a grid of samples viewed in place, a sparse grid, or scattered samples.
#pragma once

#include <memory>
#include <optional>
#include <variant>

#include "sdfcontour/input/blocked_grid.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/input/sparse_grid.h"

namespace sdfcontour {

/// A grid viewed in place (float32 or float64, never copied or widened), with whatever owns or
/// maps the memory the view reads. A view of a file mapping (map_npy) of over 256 MiB of values
/// has view.drop_pages set.
struct GridInput {
  GridView view;
  std::shared_ptr<const void> storage;  ///< keeps view.data (and view.drop_pages) alive
};

/// Scattered samples: points (n x 3) and their values (n).
struct ScatteredInput {
  Samples samples;
  double spacing = 0;  ///< the samples' spacing when known (an OpenVDB voxel size); 0: estimated
};

/// A grid held only near the surface (a sampled callable), its values already distances or
/// scaled into them by `value_scale` (measured where it was sampled: distance_value_scale of its
/// median gradient norm `gradient_norm`).
struct SparseGridInput {
  SparseGrid grid;
  std::shared_ptr<const void> storage;  ///< keeps the blocks' data alive
  double value_scale = 1;
  double gradient_norm = 1;
};

/// A grid read a block at a time (an OpenVDB level set in its file: vdb_blocked_grid): marching
/// cubes or GCP's local reconstruction run on it brick by brick, its values taken as distances.
/// Its truncation is never found from the whole grid: the options' band gives it, or else
/// `truncation` does.
struct BlockedGridInput {
  BlockedGrid grid;
  double truncation = 0;  ///< the values' own clamp (a level set's background); 0: none known
  /// Where the grid's frame lies in the world (a rotated level set: vdb_world_from_grid); the
  /// mesh and contact points are placed by it. None: the grid's positions are the world's.
  std::optional<Eigen::Affine3d> world_from_grid;
};

using SdfInput = std::variant<GridInput, ScatteredInput, SparseGridInput, BlockedGridInput>;

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
