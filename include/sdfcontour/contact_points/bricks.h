// GCP contact points brick by brick: memory bounded by a brick, not by the whole band.
//
// Space is cut into cubic bricks; each brick triangulates its own samples plus those in a halo
// around it, and keeps the contact points of its own samples only. A brick's triangulation can
// differ from the global one only where a tetrahedron's orthosphere (its empty power sphere)
// reaches out of the halo's box: a sample outside could then lie in it. So a brick certifies
// each of its samples: every incident tetrahedron's orthosphere, grown by the largest weight of
// any sample, must stay inside the box (solved exactly for tetrahedra too flat for doubles), and
// a sample on the box's convex hull must have global hull facets (no sample beyond them; in a
// flat face of the hull, such as a grid's side, a power circle inside the box).
// A brick with an uncertified sample is redone with a wider halo. Certified samples have
// exactly the global star, hence the same neighbours, gradients (sums in the same order, since
// samples keep their global order) and kept contact points: the result equals the global one.
#pragma once

#include <cmath>
#include <functional>

#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour {

struct BrickOptions {
  static constexpr int kAutoSize = -1;
  /// Brick side in spacings; 0: one triangulation of every sample; kAutoSize: auto_brick_size.
  int size = kAutoSize;
  /// First halo width in spacings (grown where a star is not certified); 0: auto_brick_halo.
  /// Samples in a shell beyond the halo, twice the largest |value| wide, are not triangulated
  /// but tested against the orthospheres that reach out of the halo's box.
  double halo = 0;
  /// When set and it becomes true, the bricks stop soon (throws Cancelled).
  const std::atomic<bool>* cancel = nullptr;
  /// A block of a larger sample set: `samples` are that set's samples inside this box (a grid
  /// brick with its halo). A star is certified only by a triangulation whose box and shell lie
  /// in it (else throws HaloTooSmall), each brick's box is then its targets' bounding box plus
  /// the halo, and `largest_value` (> 0) bounds the |value| of every sample of the larger set.
  const Bounds* within = nullptr;
  double largest_value = 0;
  /// The triangulation weighs each sample by its |value| capped at these (inside, outside; see
  /// capped_weight_values), squared; gradients and contact points read the values themselves.
  double weight_cap_inside = INFINITY, weight_cap_outside = INFINITY;
};

/// The values that weigh a band's samples in GCP's regular triangulation: |value| capped at
/// `inside` (value < 0) or `outside` (the band proper's largest |value| on that side,
/// BandSamples::core_inside / core_outside), so that the margin beyond closes the band's stars
/// without hiding its samples. Uncapped, a margin sample on a band sample's normal line (an exact
/// SDF sampled on a grid aligned with a face) has a sphere that holds the band sample's and hides
/// it: on an exact box at 32^3 no face kept a contact point and 374 of 1,146 cells fell back to
/// their edge crossings (0 capped, as with every sample triangulated).
Eigen::VectorXd capped_weight_values(const Eigen::VectorXd& values, double inside, double outside);

/// The block given to brick_contact_points (BrickOptions::within) is too small to certify the
/// flagged samples' stars: read a wider halo.
class HaloTooSmall : public Error {
 public:
  using Error::Error;
};

/// What the bricks did.
struct BrickStats {
  int bricks = 0;          ///< bricks holding samples
  int retries = 0;         ///< bricks redone with a wider halo
  long triangulated = 0;   ///< samples triangulated over all bricks (halos counted again)
  long largest_brick = 0;  ///< samples in the largest triangulation
  int size = 0;            ///< the brick side used, in spacings
};

/// The first halo (in spacings) for samples whose largest |value| is `largest`: largest / spacing
/// rounded up, + 2. From measurement: the stars of the band's outermost samples reach about that
/// far (bunny 256³, largest 4 spacings: 5 needs no retry, 4 retries 5 of 8 bricks; 128³,
/// largest 5: 7 none, 6 one; a sphere at 72³, largest 4: 6 none, 5.97 twelve). The exact test
/// against the shell's samples lets it be this thin; bounding every outside weight by the
/// largest needed twice the largest |value|.
double auto_brick_halo(double largest, double spacing);

/// The brick side (in spacings) for `points` (n x 3) at `spacing` when `threads` run them: the
/// largest of 256, 192, 160, 128, 96 that still makes at least 4 bricks per thread with at most
/// kMaxBrickSamples samples of their own each, else 64. Larger bricks triangulate fewer halo
/// samples again (bunny 512³ on 2 threads: 64 → 48 s, 128 → 32 s, 256 → 29 s for the contact
/// points; docs/scale.md), and 4 bricks per thread keep the threads busy to the end.
int auto_brick_size(const PointMatrix& points, double spacing, int threads);
constexpr long kMaxBrickSamples = 1'500'000;

/// GCP contact points of `samples` (positions n x 3, values n), computed brick by brick with the
/// regular triangulation, `gradient` and `contact` options: equal to
/// gradient_contact_points(points, values, vertex_gradients(points, values, regular), regular)
/// of the global regular triangulation. `spacing` is the unit of `options` (the grid spacing).
/// Bricks run in parallel (TBB). `progress(done, total)` is called as bricks finish (from any
/// thread, serialised). With `only` (n flags), just the flagged samples give contact points, and
/// only they need a certified star. Throws Error for bad options.
ContactPoints brick_contact_points(const Samples& samples, double spacing,
                                   const GradientOptions& gradient,
                                   const ContactPointOptions& contact, const BrickOptions& options,
                                   BrickStats* stats = nullptr,
                                   const std::function<void(int, int)>& progress = {},
                                   const std::vector<char>* only = nullptr);

}  // namespace sdfcontour
