// Internal: the local reconstruction's mesh with global names, for bricks (local_brick.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sdfcontour/reconstruction/local_reconstruction.h"

namespace sdfcontour::detail {

/// local_reconstruction()'s mesh, each vertex and triangle named as in the whole grid, so that a
/// block of a grid (GridGeometry::first) names them as the whole grid's run does.
struct KeyedLocalMesh {
  Mesh mesh;
  /// Per vertex: 4 * global cell + polygon for a cell's vertex; for a segment vertex,
  /// 4 * (the whole grid's cell count) + its segment key (DualPolygons::extra_keys).
  std::vector<std::uint64_t> vertex_key;
  std::vector<std::uint64_t> triangle_edge;  ///< per triangle: its polygon's grid edge key
  std::vector<std::uint8_t> triangle_rank;   ///< per triangle: its rank in the polygon
  /// Per cell vertex (the first rows): placed from crossings, at a feature (2: at a corner that
  /// its samples share, exact), clamped, field miss.
  std::vector<std::array<char, 4>> flags;
  /// Per cell vertex: the mean of its polygon's edge crossings, a place inside the cell that no
  /// quadric moves (where the quadrics' vertices make the mesh cross itself).
  PointMatrix crossing_means;
};

/// `cell_box` (if set): only the cells [box[0], box[1]) of `grid` (its own cell indices) and the
/// grid edges whose four cells lie there; a brick reads its owned edges and a ring, not its halo.
KeyedLocalMesh keyed_local_reconstruction(
    const GridView& grid, const PointMatrix& points, const PointMatrix& normals,
    const LocalReconstructionOptions& options, LocalReconstructionStats* stats_out,
    const Eigen::VectorXd& depths, const std::array<std::array<int, 3>, 2>* cell_box = nullptr);

}  // namespace sdfcontour::detail
