// Side repair: the last samples on the wrong side of a finished mesh, moved to their sides by
// smooth local dents that cross nothing.
//
// Carving's triangle rounds move one feature (a triangle, edge or vertex) per sample, and the
// untangling undoes every move that pushed one sheet through another. Where a gap or notch is
// narrower than a spacing (the plane's wing at 32^3 and 64^3, a crease of the boot, the cat and the
// goat head at 32^3), the reconstruction fills it, the one-feature move is a spike the carving
// holds back or the untangling undoes, and an outside sample stays inside the mesh
// (docs/carving.md). Here each such sample dents the sheet nearest to it as a whole patch, with a
// smooth falloff, and the dent is kept only if the mesh still crosses nothing and no sample near it
// lands on the wrong side.
#pragma once

#include <Eigen/Core>

#include "sdfcontour/types.h"

namespace sdfcontour {

struct SideRepairOptions {
  /// Samples with |value| up to this many spacings are checked.
  double reach = 3;
  /// Geodesic radii of the dents tried, in spacings: `radius`, then doubled `radius_doublings`
  /// times (the smallest first: the plane's tail at 32^3 needs a quarter spacing).
  double radius = 0.25;
  int radius_doublings = 3;
  /// At most this many wrong-side samples are repaired (each costs a crossing test); the rest
  /// are counted as left.
  int max_samples = 256;
};

struct SideRepairStats {
  long wrong_side = 0;  ///< samples within reach on the wrong side before the repair
  long repaired = 0;    ///< of those, samples a dent put on their side
  long left = 0;        ///< samples still on the wrong side
  long vertices_moved = 0;
};

/// Moves the vertices of `mesh` (closed, oriented, free of self-intersections; in place) so that
/// the samples (points n x 3, values n, negative inside) within options.reach spacings of the
/// surface lie on their own sides: for each that does not, ascending, the vertices within a
/// geodesic radius R of its nearest point whose normals face the same way move along the nearest
/// feature's normal, by (1 - (d/R)^2)^2 of the move that puts the sample |value| beyond the sheet
/// (all by the feature's move, or each to the plane |value| behind the sample; else half that
/// depth), again for the sheet nearest next (up to 3). A dent is kept only if the sample then lies
/// on its side, no sample the moved triangles swept over has come to the wrong side, no two
/// triangles sharing an edge fold onto each other and no moved triangle crosses another; else the
/// next radius or shape is tried. The connectivity is unchanged; the result does not depend on the
/// thread count. Throws Error for mismatched sizes, non-finite samples or a spacing that is not
/// positive.
SideRepairStats repair_sample_sides(Mesh& mesh, const PointMatrix& points,
                                    const Eigen::VectorXd& values, double spacing,
                                    const SideRepairOptions& options = {});

}  // namespace sdfcontour
