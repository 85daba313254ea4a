// Midpoint subdivision: each triangle into four, a new vertex at the middle of each edge.
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour {

/// `mesh` with each triangle (a, b, c) split into (a, ab, ca), (ab, b, bc), (ca, bc, c) and
/// (ab, bc, ca), where xy is a new vertex at the middle of edge xy, shared by the triangles on
/// both sides of the edge. The old vertices keep their ids; new ones follow in ascending order of
/// their edges (the smaller vertex id first). Closed, manifold and oriented meshes stay so.
Mesh midpoint_subdivision(const Mesh& mesh);

}  // namespace sdfcontour
