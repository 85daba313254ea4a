// Internal: each triangle of a keyed mesh cut into 4^s by the lattice of 2^s segments per edge,
// the new vertices named globally (local_brick.h's VertexKey), so that two bricks that share an
// edge compute and name its vertices alike.
#pragma once

#include <cstdint>
#include <vector>

#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

/// A keyed triangle soup: vertex rows with keys, triangles with a global name each (ascending
/// names give the whole grid's order).
struct KeyedTriangles {
  PointMatrix vertices;
  std::vector<std::uint64_t> vertex_key;  ///< per vertex (level 0: KeyedLocalMesh's keys)
  std::vector<char> on_feature;  ///< per vertex: placed on an edge or corner (2: a shared corner)
  TriangleMatrix triangles;
  std::vector<std::uint64_t> triangle_name;  ///< per triangle: edge * 8 + rank, ascending
};

/// The subdivided mesh: vertices in ascending key order, triangles in the order of their parents'
/// names (each parent's children in a fixed order). Edge vertices are computed from the edge's
/// ends in key order, so every triangle on an edge gets the same bits.
struct SubdividedMesh {
  Mesh mesh;
  std::vector<VertexKey> keys;
  std::vector<std::uint64_t> parent;  ///< per triangle: its parent's name
  /// Per vertex: a feature vertex (2 at a corner that samples share), or 1 on the segment
  /// between two (along a sharp edge).
  std::vector<char> on_feature;
};

SubdividedMesh lattice_subdivision(const KeyedTriangles& in, int levels);

}  // namespace sdfcontour::detail
