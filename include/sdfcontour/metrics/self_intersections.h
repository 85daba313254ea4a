// Triangles of a mesh that cross each other, and undoing the vertex moves that made them.
// Projection and carving move vertices a fraction of a spacing; where a part is thinner than
// that, a move can push one sheet through another and leave a self-intersecting mesh (which
// breaks booleans, tetrahedral meshing and inside tests).
#pragma once

#include <array>
#include <functional>
#include <utility>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Pairs (s, t), s < t, ascending, of triangles of `mesh` that intersect other than in the
/// vertices and edge they share: triangles with no common vertex that meet, triangles with one
/// common vertex whose opposite edges cut the other triangle, and triangles sharing an edge that
/// fold onto each other (coplanar, on the same side of it). Degenerate (zero-area) triangles are
/// not tested. With `watch` (one flag per triangle), only
/// pairs with at least one flagged triangle are reported. Exact predicates (CGAL); parallel
/// (TBB), the same result for any thread count.
std::vector<std::pair<int, int>> self_intersecting_triangles(
    const Mesh& mesh, const std::vector<char>* watch = nullptr);

namespace detail {
/// Whether two triangles, given by their corners and vertex ids (an id they share is a corner
/// they share), meet other than in what they share: the test self_intersecting_triangles makes
/// of each pair. Exact predicates.
bool triangles_cross(const std::array<Eigen::Vector3d, 3>& s, const std::array<int, 3>& s_ids,
                     const std::array<Eigen::Vector3d, 3>& t, const std::array<int, 3>& t_ids);
/// Whether a triangle's corners are collinear (exact): the search leaves such triangles out.
bool collinear_corners(const std::array<Eigen::Vector3d, 3>& corners);
}  // namespace detail

/// What revert_self_intersections did.
struct UntangleStats {
  int rounds = 0;                ///< rounds of tests
  int vertices_reverted = 0;     ///< vertices moved back to where they were
  long intersections_found = 0;  ///< intersecting pairs in the first round
  long intersections_left = 0;   ///< pairs that moving back could not remove (`before` had them)
};

/// Moves back to `before` (the mesh's vertices before some stage moved them: same rows, same
/// triangles) every moved vertex of a triangle that intersects another, round after round over
/// the triangles around the vertices moved back, until no such triangle is left, or for at most
/// `max_rounds` rounds (0: no limit; a fixed number bounds how far a vertex's result reaches,
/// as bricks need). Each round's decisions are taken from the positions it started with.
/// `before` is taken as free of self-intersections; pairs it had already are counted as left.
/// `reverted` (optional) receives a flag per vertex moved back. `progress` (optional) is called
/// with (triangles tested, triangles to test) in the first round, the search's bulk (later rounds
/// test the few triangles around the vertices moved back). Throws Error if `before` does not
/// match the mesh.
UntangleStats revert_self_intersections(Mesh& mesh, const PointMatrix& before, int max_rounds = 0,
                                        std::vector<char>* reverted = nullptr,
                                        const std::function<void(long, long)>& progress = {});

}  // namespace sdfcontour
