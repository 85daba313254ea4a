// One closed surface from a mesh whose closed parts overlap (a scene of touching objects, a
// model exported as separate shells): the boundary of the union of the solids they bound.
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour {

/// What union_of_overlapping_parts did.
struct MeshUnionStats {
  int parts = 0;            ///< connected components of the input
  int parts_united = 0;     ///< parts merged into others (0: nothing overlapped)
  long crossings_left = 0;  ///< pairs of crossing triangles left: inside a part, or not united
};

/// The boundary of the union of the solids bounded by the closed parts (connected components)
/// of `mesh`: parts whose triangles cross are united by CGAL's exact corefinement, and the rest
/// are kept as they are, so that the inner faces of overlapping parts are gone and a signed
/// distance sampled from the result is a distance. A part that crosses itself, or that bounds no
/// positive volume (its faces turned inward), cannot be united; it is kept, and its crossings are
/// counted in `stats`. `mesh` must be closed and consistently
/// oriented (require_closed_mesh). Deterministic.
Mesh union_of_overlapping_parts(const Mesh& mesh, MeshUnionStats* stats = nullptr);

}  // namespace sdfcontour
