// Sphere carving: a mesh moved out of the empty spheres of signed distance samples.
//
// A sample p with an exact signed distance value v certifies that the open ball of radius |v|
// around p holds no surface. A reconstructed mesh that cuts into such a ball is wrong there by at
// least how deep it cuts: carving moves each such vertex radially onto the sphere of the ball it
// enters deepest, which is never farther from the true surface than the vertex was along that
// direction. Poisson's smooth surface bulges into the spheres a little all over (GCP's L1 at 32^3
// falls by 10-12% on the shared meshes, docs/carving.md) and deeply where a thin part is
// under-sampled (the samples then end on the wrong side of the mesh).
#pragma once

#include <Eigen/Core>

#include "sdfcontour/types.h"

namespace sdfcontour {

struct CarvingOptions {
  /// Rounds of pushing vertices out (a vertex pushed out of one ball can enter another).
  int passes = 3;
  /// A triangle's normal may turn by at most this many degrees in a round; where it would turn
  /// more (two sides of a thin part pushed through each other), its vertices move half as far,
  /// up to `halvings` times, then not at all.
  double max_turn_degrees = 60;
  int halvings = 8;
};

struct CarvingStats {
  long vertices_moved = 0;  ///< distinct vertices that moved, over all rounds
  double largest_move = 0;  ///< the longest total displacement of a vertex
  long held_back = 0;       ///< vertices kept short of a sphere to keep their triangles' sides
  int passes = 0;           ///< rounds run (the last one moved nothing, or `passes` ran out)
};

/// Moves the vertices of `mesh` (in place) out of the balls of the samples: ball i has centre
/// points.row(i) (n x 3) and radius |values[i]| (n). `spacing` (> 0) is the samples' spacing,
/// the cell of the index used to find the vertices near a ball. Triangles are unchanged. The
/// result does not depend on the thread count. Throws Error for mismatched sizes, a non-finite
/// value, or a spacing that is not positive.
CarvingStats carve_mesh(Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values,
                        double spacing, const CarvingOptions& options = {});

}  // namespace sdfcontour
