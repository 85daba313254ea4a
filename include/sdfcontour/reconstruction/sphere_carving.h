// Sphere carving: a mesh moved out of the empty spheres of signed distance samples.
//
// A sample p with an exact signed distance value v certifies that the open ball of radius |v|
// around p holds no surface. A reconstructed mesh that cuts into such a ball is wrong there by at
// least how deep it cuts: carving moves each such vertex radially onto the sphere of the ball it
// enters deepest, which is never farther from the true surface than the vertex was along that
// direction. Poisson's smooth surface bulges into the spheres a little all over (GCP's L1 at 32^3
// falls by 10-12% on the shared meshes, docs/carving.md) and deeply where a thin part is
// under-sampled (the samples then end on the wrong side of the mesh). Triangle rounds then move
// the triangles, edges and vertices nearest to the samples next to the surface whose balls they
// cut or whose side they get wrong (wrong-side samples on the shared meshes at 32^3 and 64^3:
// 66 and 141 with vertices alone, 1 and 1 with them).
#pragma once

#include <Eigen/Core>
#include <functional>

#include "sdfcontour/types.h"

namespace sdfcontour {

struct CarvingOptions {
  /// Rounds of pushing vertices out (a vertex pushed out of one ball can enter another), before
  /// the triangle phase and again, on the vertices it moved, after it.
  int passes = 3;
  /// A triangle's normal may turn by at most this many degrees in a round; where it would turn
  /// more (two sides of a thin part pushed through each other), its vertices move half as far,
  /// up to `halvings` times, then not at all.
  double max_turn_degrees = 60;
  int halvings = 8;
  /// Rounds of the triangle phase, after the vertex rounds (0: none). A ball can hold part of a
  /// triangle with no vertex in it, and a sample close to the surface can end on the wrong side of
  /// the mesh: each sample within `side_reach` spacings of the surface (|value|) that does either
  /// moves the vertices of the mesh's nearest feature (triangle, edge or vertex) along its normal
  /// until the sample would lie on its own side, |value| away. The vertices it moved then leave
  /// any ball they entered (vertex rounds), and up to as many rounds put the samples near those
  /// moves back on their sides (their balls alone may stay cut, by a hair).
  int side_passes = 12;
  double side_reach = 1;
  /// Called with (samples done, samples) over the first round of vertex pushes (of every vertex,
  /// the bulk of the work), from any thread, one call at a time.
  std::function<void(long, long)> progress;
};

struct CarvingStats {
  long vertices_moved = 0;  ///< distinct vertices that moved, over all rounds
  double largest_move = 0;  ///< the longest total displacement of a vertex
  long held_back = 0;       ///< vertices kept short of a sphere to keep their triangles' sides
  int passes = 0;           ///< vertex rounds run (before and after the triangle phase)
  /// Triangle phase: samples on the wrong side of the mesh or with part of a triangle inside their
  /// ball, before its first round and after its last; rounds that moved vertices.
  long side_violations = 0, side_violations_left = 0;
  /// Samples the last check found on the wrong side. Later rounds check only the samples that
  /// failed or lie near the last moves, so this and side_violations_left count among those.
  long wrong_side_left = 0;
  int side_passes = 0;
};

/// Moves the vertices of `mesh` (in place) out of the balls of the samples: ball i has centre
/// points.row(i) (n x 3) and radius |values[i]| (n), then (options.side_passes) moves the
/// triangles near the surface off the balls and behind the samples' own sides. `spacing` (> 0) is
/// the samples' spacing, the cell of the index used to find the vertices near a ball and the unit
/// of options.side_reach. The triangles' connectivity is unchanged. The
/// result does not depend on the thread count. Throws Error for mismatched sizes, a non-finite
/// value, or a spacing that is not positive.
CarvingStats carve_mesh(Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values,
                        double spacing, const CarvingOptions& options = {});

}  // namespace sdfcontour
