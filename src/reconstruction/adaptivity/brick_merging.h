// Internal: a mesh merged brick by brick (adaptivity), the bricks in parallel.
#pragma once

#include <vector>

#include "reconstruction/adaptivity/edge_collapse.h"
#include "reconstruction/adaptivity/merge_quadric.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// A mesh being merged, with one entry per vertex in each vector.
struct MergeState {
  Mesh mesh;
  std::vector<MergeQuadric> quadrics;  ///< the summed quadric of the vertices it merged
  std::vector<char> frozen;            ///< no merge may move it
  std::vector<int> source;             ///< its index in the mesh the merging started from
};

/// One pass of merging over bricks: the lattice of cubes of side `brick_side` whose corners lie
/// at `origin` + (shift + integers) * brick_side. A vertex belongs to the brick it lies in; each
/// brick collapses the edges between its vertices whose neighbours all belong to it too (the
/// star of such a vertex stays inside its brick, so no two bricks change one triangle, and each
/// brick's piece, with the stars of its vertices next to them, decides the link condition
/// exactly). The bricks run in parallel, each sequential, and are joined in brick order: the
/// same state for any thread count. Returns the number of merges.
long merge_in_bricks(MergeState& state, const Eigen::Vector3d& origin, double brick_side,
                     double shift, const CollapseLimits& limits);

}  // namespace sdfcontour::detail
