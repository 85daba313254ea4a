// Internal: each triangle of a keyed mesh cut into 4^s by the lattice of 2^s segments per edge,
// the new vertices named globally (local_brick.h's VertexKey), so that two bricks that share an
// edge compute and name its vertices alike.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

struct VertexTriangles;
struct ChordOffsets;

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
  std::vector<int> child;             ///< per triangle: its rank among its parent's, < 256
  /// Per vertex: a feature vertex (2 at a corner that samples share), or 1 on the segment
  /// between two (along a sharp edge).
  std::vector<char> on_feature;
};

SubdividedMesh lattice_subdivision(const KeyedTriangles& in, int levels);

/// A vertex on a level-0 edge (key[1] != 0, not inside a triangle): the key of the edge's end
/// with the larger key (key[0] is the other end's).
inline std::uint64_t far_end_key(const VertexKey& key) {
  return key[1] / 64 - 1;
}

/// Whether the edge (x, y) of `sub`, with `normals` its vertex normals, sags by more than
/// `limit` (its length times its ends' normals' turn / 8, a circular arc's sag), off sharp edges
/// and creases.
bool chord_sags(const SubdividedMesh& sub, const PointMatrix& normals, int x, int y, double limit);

/// Per vertex of `sub`: a corner that samples share (on_feature 2), which stays where it is.
std::vector<char> shared_corners(const SubdividedMesh& sub);

/// split_curved_edges' mesh, and per vertex the two vertices of `fine` whose midpoint it is (the
/// same one twice for fine's own).
struct SplitMesh {
  SubdividedMesh sub;
  std::vector<std::array<int, 2>> source;
};

/// One more level where it pays: each edge (x, y) of `fine` (lattice_subdivision(in, levels),
/// levels <= 3, its vertices moved since) for which split(x, y) holds (x < y: asked once per
/// edge, from any thread) gets its midpoint, named as one more uniform level would name it, and
/// each triangle is cut at its split edges into 1-4. Vertices in ascending key order, triangles
/// by parent, then by rank among the parent's.
SplitMesh split_curved_edges(const KeyedTriangles& in, const SubdividedMesh& fine, int levels,
                             const std::function<bool(int, int)>& split);

/// The local reconstruction's use of it (LocalBrickOptions::split_sag): after `sub`
/// (lattice_subdivision(near, levels)) was projected by `projector`, each edge whose chord sags
/// by more than `limit` (its length times its ends' normals' turn / 8, a circular arc's sag) is
/// split and the new vertices projected by it; `reconstructed` (the positions the untangling
/// returns vertices to: the new ones at their edges' midpoints) and `corners` (per vertex: a shared
/// corner) follow the new numbering. `around`: sub.mesh's triangles around each vertex. With
/// `chords` (the first projection's), the vertices kept from before the split have their chord
/// offsets set again for their new, smaller triangles, and `chords` follows the new numbering.
void split_sagging_edges(const KeyedTriangles& near, int levels, double limit,
                         const ContactProjector& projector, const LocalBrickOptions& options,
                         const VertexTriangles& around, SubdividedMesh& sub,
                         PointMatrix& reconstructed, std::vector<char>& corners,
                         ChordOffsets* chords = nullptr);

}  // namespace sdfcontour::detail
