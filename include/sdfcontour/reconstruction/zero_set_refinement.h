// Vertices refined on the grid's own zero set where its values are no distances.
//
// GCP's contact point c = p - value * n assumes |grad| = 1: a neural SDF's slope drifts off 1
// (its bunny fixture: 10th-90th percentile 0.81-1.04 next to the surface), so a point from a
// sample d away misses by d times that drift, 0.03-0.2 spacings from samples 1-3 spacings out,
// and the sample's sphere (the carving) is not empty. There the grid's values still say where
// the zero set is: each such vertex moves onto the zero set of the grid's tricubic interpolant.
// Where the values are distances, the contact points beat any interpolant (at sharp edges, where
// the field has kinks), so the vertices stay: the pipeline judges the whole grid
// (auto_approximate_distances), or each vertex measures how far the samples near it are from
// distances to the mesh itself (ZeroSetRefinementOptions::mismatch).
#pragma once

#include <limits>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

struct ZeroSetRefinementOptions {
  /// Samples with |value| between these many spacings measure the values against distances.
  double shell_inner = 1.0;
  double shell_outer = 2.5;
  /// A vertex reads the samples whose nearest mesh point lies within this many spacings of it.
  double gather_radius = 1.5;
  /// Positive: only the vertices whose samples' mean | |value| / distance to the mesh - 1 |
  /// exceeds this move (exact distances to the shared meshes: a median of 0.003-0.013 at 64^3 on
  /// the local reconstruction's cells; the neural bunny 0.05). 0: every vertex, unmeasured.
  double mismatch = 0;
  /// Fewer samples than this leave a vertex as it is.
  int min_samples = 3;
  int newton_steps = 4;
  /// A vertex that would move farther than this many spacings stays (the interpolant's zero set
  /// is elsewhere: a part thinner than the grid).
  double max_move = 0.5;
  /// Values at or beyond this size carry no distance (a truncated grid); an interpolation
  /// touching one is not used.
  double truncation = std::numeric_limits<double>::infinity();
};

/// ZeroSetRefinementOptions::truncation for a grid whose band found `truncation` in its values
/// scaled by `value_scale` (BandOptions::value_scale): the interpolant reads the grid's values as
/// given.
double grid_truncation(const Truncation& truncation, double value_scale);

/// Per vertex of `mesh`, the mean of | |value| / distance - 1 | over the `samples` (points (n, 3),
/// values (n)) with |value| in [shell_inner h, shell_outer h], where distance is the sample's
/// distance to the mesh, over those samples whose nearest mesh point lies within gather_radius
/// h of the vertex; NaN where fewer than min_samples do. Parallel; the same for any thread count.
std::vector<double> distance_mismatch(const Mesh& mesh, const Samples& samples, double h,
                                      const ZeroSetRefinementOptions& options);

/// The field's Catmull-Rom tricubic interpolant at p (3) and its gradient; false where the
/// 4x4x4 stencil leaves the grid (a block: its own samples) or holds a value at or beyond
/// `truncation` in size.
bool tricubic_value(const GridView& grid, const Eigen::Vector3d& p, double truncation,
                    double& value, Eigen::Vector3d& gradient);

struct ZeroSetRefinementStats {
  long measured = 0;  ///< vertices with enough samples to measure
  long flagged = 0;   ///< of those, whose values are no distances
  long moved = 0;     ///< flagged vertices moved onto the interpolant's zero set
};

/// Moves each vertex i with which[i] set by Newton steps v -= f(v) grad f / |grad f|^2 on the
/// tricubic interpolant of `grid`, unless the interpolant is unavailable on the way or the move
/// exceeds max_move spacings (the vertex then stays). Sets moved[i] (resized to V's rows) for
/// the vertices moved. Parallel; the same for any thread count.
long refine_on_zero_set(PointMatrix& V, const std::vector<char>& which, const GridView& grid,
                        const ZeroSetRefinementOptions& options,
                        std::vector<char>* moved = nullptr);

/// Both: the vertices of `mesh` (not `fixed`, if given) whose samples are no distances (every
/// vertex for mismatch 0), moved; `flagged` (if given) marks all those, `moved` those moved.
ZeroSetRefinementStats refine_where_values_are_no_distances(
    Mesh& mesh, const Samples& samples, const GridView& grid,
    const ZeroSetRefinementOptions& options, const std::vector<char>* fixed = nullptr,
    std::vector<char>* moved = nullptr, std::vector<char>* flagged = nullptr);

}  // namespace sdfcontour
