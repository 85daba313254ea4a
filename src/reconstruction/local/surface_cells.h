// Internal: the grid cells the zero level set crosses, their marching-cubes polygons, and the
// quads of the dual mesh (one per sign-changing grid edge inside the grid).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "sdfcontour/input/samples.h"

namespace sdfcontour::detail {

/// A cell with corners of both signs. Cell (i, j, k) spans samples (i..i+1, j..j+1, k..k+1).
struct ActiveCell {
  std::int64_t key = 0;        ///< (i * (ny - 1) + j) * (nz - 1) + k
  int first_vertex = 0;        ///< its first polygon's vertex id
  std::uint8_t inside = 0;     ///< CubeCase::inside
  std::uint8_t connected = 0;  ///< CubeCase::insides_connected
  std::int8_t polygon_count = 0;
  std::array<std::int8_t, 12> polygon_of_edge{};  ///< local edge -> its polygon, -1: no crossing
};

/// One cell's polygons with their edge crossings (linear interpolation) and outward directions.
struct CellPolygons {
  int count = 0;
  std::array<int, 5> first_crossing{};  ///< polygon q's crossings: [first[q], first[q + 1])
  std::array<Eigen::Vector3d, 12> crossing, crossing_normal;  ///< normals: the field's gradient
  std::array<Eigen::Vector3d, 4> outward;  ///< sum of the polygon's crossing normals
};

/// A sign-changing grid edge's polygon: the vertices of the four cells around it, counter-clockwise
/// seen from the edge's outside end. Where two face-adjacent cells' polygons meet along both of
/// the face's segments (an ambiguous face that one polygon crosses twice on each side), the two
/// vertices would be joined twice; each segment then gets a vertex of its own between them, so a
/// polygon has up to 8 vertices.
struct DualPolygons {
  std::vector<std::array<int, 8>> vertices;
  std::vector<std::int8_t> size;
  std::vector<std::uint64_t> edge;  ///< each polygon's grid edge: 3 * global low point + axis
  std::vector<Eigen::Vector3d> edge_point;  ///< where the values' linear interpolant crosses it
  /// The segment vertices' positions, numbered after the cells' vertices, and their global keys
  /// ((3 * global face point + axis) * 4 + corner), ascending.
  std::vector<Eigen::Vector3d> extra_positions;
  std::vector<std::uint64_t> extra_keys;
};

struct SurfaceCells {
  GridView grid;
  std::array<int, 3> cell_dims{};  ///< grid dims minus one
  Eigen::Vector3d min, spacing;    ///< the whole grid's first sample and spacing
  std::array<int, 3> first{};      ///< a block's offset in its whole grid (GridGeometry::first)
  /// The cells searched, [box_lo, box_hi) in the grid's cell indices: `active` holds only these.
  std::array<int, 3> box_lo{}, box_hi{};
  std::vector<ActiveCell> active;  ///< ascending keys

  std::int64_t key(const std::array<int, 3>& c) const {
    return (std::int64_t(c[0]) * cell_dims[1] + c[1]) * cell_dims[2] + c[2];
  }
  std::array<int, 3> cell_of_key(std::int64_t key) const;
  bool contains_cell(const std::array<int, 3>& c) const {
    for (int d = 0; d < 3; ++d)
      if (c[d] < 0 || c[d] >= cell_dims[d]) return false;
    return true;
  }
  /// The position of cell c's lowest corner.
  Eigen::Vector3d corner(const std::array<int, 3>& c) const {
    return min +
           Eigen::Vector3d(c[0] + first[0], c[1] + first[1], c[2] + first[2]).cwiseProduct(spacing);
  }
  /// Cell c's index in the whole grid ((i * (nx - 1) + j) * (nz - 1) + k, global i, j, k).
  std::uint64_t global_cell(const std::array<int, 3>& c) const;
  /// Grid point p's index in the whole grid (C order).
  std::uint64_t global_point(const std::array<int, 3>& p) const;
  /// The key of the cell holding p (clamped to the grid).
  std::int64_t key_of_point(const Eigen::Vector3d& p) const;
  /// Index into `active` of the cell with this key, or -1.
  long find(std::int64_t key) const;
  int vertex_count() const {
    return active.empty() ? 0 : active.back().first_vertex + active.back().polygon_count;
  }
  CellPolygons polygons(const ActiveCell& cell) const;
  /// The dual mesh's polygons (dual_polygons.cpp). With `every_ambiguous_face`, each segment of a
  /// face that the surface crosses four times gets a vertex (for edge fans: each triangle then
  /// stays in one cell); else only where both cells would join the same two vertices twice.
  DualPolygons dual_polygons(bool every_ambiguous_face = false) const;
};

/// Grid point of cell `cell`'s corner c (bits x=1, y=2, z=4), and a grid point's value.
std::array<int, 3> corner_of(const std::array<int, 3>& cell, int c);
double value_at(const GridView& grid, const std::array<int, 3>& p);

/// The cells of `grid` that its zero level set crosses (inside: value < 0), in key order; with
/// `box`, only those among the cells [box[0], box[1]) (clipped to the grid's), whose keys and
/// positions stay the whole grid's.
SurfaceCells find_surface_cells(const GridView& grid,
                                const std::array<std::array<int, 3>, 2>* box = nullptr);

}  // namespace sdfcontour::detail
