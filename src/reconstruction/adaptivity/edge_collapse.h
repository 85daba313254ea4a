// Internal: one mesh (or a brick's piece of one) merged by quadric edge collapse.
#pragma once

#include <vector>

#include "reconstruction/adaptivity/merge_quadric.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

struct CollapseLimits {
  double spacing = 0;           ///< the grid's spacing h
  double tolerance = 0;         ///< in spacings: a merge stands while its quadric is under this^2
  double max_normal_turn = 45;  ///< degrees a merge may turn a triangle of its star
};

/// `mesh` (2-manifold, oriented; it may have borders, whose vertices must be `frozen`) with its
/// edges collapsed, cheapest first, over one `quadrics` entry per vertex. A collapse must keep
/// the link condition, turn no triangle of its star past the normal bound, and cross none of the
/// triangles of its star or around it. No merge moves a vertex whose `frozen` entry is set. On
/// return `quadrics[source[r]]` is the summed quadric of output vertex r, and `source[r]` its
/// index in `mesh` (increasing in r).
/// Sequential and deterministic. Returns the merged mesh; `merges` counts the collapses.
Mesh collapse_edges(const Mesh& mesh, std::vector<MergeQuadric>& quadrics,
                    const std::vector<char>& frozen, const CollapseLimits& limits,
                    std::vector<int>& source, long& merges);

}  // namespace sdfcontour::detail
