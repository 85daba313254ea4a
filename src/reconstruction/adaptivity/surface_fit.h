// Internal: a merged mesh's vertices moved so that its triangles follow the mesh it was merged
// from (adaptivity's last step).
#pragma once

#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

struct SurfaceFitOptions {
  int rounds = 6;          ///< damped Jacobi rounds of the least squares
  double max_move = 0.25;  ///< in spacings: no vertex moves farther from where the merge put it
};

/// Moves the vertices of `merged` (closed, oriented) whose `fixed` entry is 0 (one per vertex)
/// so that its triangles pass closer to the vertices of `dense` (the mesh it was merged from),
/// in the least squares, the feet of those vertices on their nearest triangles held at their
/// barycentric coordinates (the fitting step of Hoppe et al., "Mesh optimization", 1993). A
/// merged vertex at the minimum of its region's quadric lies off the curved surface between its
/// neighbours; here the triangles straddle it instead. A dense vertex farther than a spacing
/// from `merged`, or whose normal turns more than 60 degrees from its triangle's (another
/// sheet), is left out. Moves that make triangles cross are undone. Parallel; the same result
/// for any thread count. Returns the number of vertices moved.
long fit_merged_vertices(Mesh& merged, const Mesh& dense, const std::vector<char>& fixed, double h,
                         const SurfaceFitOptions& options = {});

}  // namespace sdfcontour::detail
