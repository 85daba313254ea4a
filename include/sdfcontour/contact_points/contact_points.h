// Contact points: where each sample's sphere of radius |value| touches the surface,
// c = p - value * n with n the unit gradient, kept only if c lies in no other sample's sphere.
#pragma once

#include <vector>

#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/input/builtin_shapes.h"

namespace sdfcontour {

struct ContactPointOptions {
  /// Near-tie tolerance tau. A candidate c of sample i is discarded when it lies inside a
  /// neighbour n's sphere by more than tau times their distance:
  ///   |c - p_n| < |value_n| - tau * |p_n - p_i|.
  /// Samples of a true SDF put many contact points exactly on a neighbour's sphere (samples on
  /// one normal line share their contact point); round-off then decides them at random. tau = 0
  /// is the strict test.
  double tie_tolerance = 1e-6;
  /// "+FN": when the averaged gradient's point is discarded, try each incident tet's own gradient
  /// (in ascending tet order) until one gives a point that passes.
  bool try_tet_gradients = false;
  /// A sample whose triangulation neighbours miss its gradient's linear prediction by more than
  /// this many times their distance (|value_j - value_i - g.(p_j - p_i)| > s |p_j - p_i|) straddles
  /// a crease or a medial axis: its averaged gradient mixes the two sides, and its point would
  /// land off the surface where no sphere refutes it. It gets no point. 0: no test (the paper).
  double max_slope_miss = 0;
  /// A candidate inside a neighbour's sphere is pushed out of the spheres it lies in and back
  /// onto its own sphere, for up to this many rounds, and kept if it then passes the test: at a
  /// convex edge or corner the only point of the sphere that no neighbour's sphere holds is the
  /// feature, which an averaged gradient misses. 0: discarded (the paper).
  int sphere_slide_rounds = 0;
  /// A sample without a point takes the vertex of its power cell that lies on its sphere: the
  /// orthocentre of an incident tetrahedron of samples on its side whose power is within this
  /// fraction of value_i^2 of zero. That vertex is on all four spheres (to the tolerance) and,
  /// the orthosphere being empty, in no other sample's sphere (tested against the neighbours'
  /// spheres as any point is, since the triangulation may weigh a margin sample less than its
  /// value): where a sphere is (nearly) covered by its neighbours', what is left of it is there. At
  /// a convex corner every outside sample's sphere passes through the corner, which no averaged
  /// gradient finds. 0: none (the paper).
  double power_vertex_tolerance = 0;
  /// Where a sample is left with only an inexact power vertex (no exact meeting of spheres, as at
  /// a corner or edge of exact data, and no slide), its candidate is kept instead if no
  /// neighbour's sphere holds it deeper than this fraction of |value_i|: on a smooth surface a
  /// gradient a little off puts the point in the thin gap between the spheres and the surface, a
  /// few thousandths of a spacing off, where the gap's power vertex lies farther (torus 64^3:
  /// 0.003 h against 0.016 h at the median). 0: the power vertex (the paper: no point).
  double near_miss_tolerance = 0;
  /// The lattice's points only: a sample farther from the surface than this many spacings
  /// (|value| > rescue_reach * h) keeps its candidate or none, without the slide and the power
  /// vertex, which read hundreds of spheres there. 0: every sample.
  double rescue_reach = 0;
  /// The lattice's points only: look for four values along an axis whose squares are exactly
  /// quadratic (a distance to a line or a point, as next to a polyhedron's edges and corners),
  /// which reads a third sample along the axis where the stencil has none. The local bricks turn
  /// it off for float32 values, whose rounding (6e-8) never meets the test's 1e-13: the same
  /// points, without the reads (bunny 512^3's contact points took 1.22x the time with them).
  bool exact_wedge_slopes = true;
};

/// Oriented contact points and where they came from.
struct ContactPoints {
  PointMatrix points;        ///< k x 3 contact points
  PointMatrix normals;       ///< k x 3 unit outward normals
  std::vector<int> samples;  ///< k source sample indices, ascending
  int hidden = 0;            ///< samples that are not triangulation vertices (no point)
  int zero_gradient = 0;     ///< visible samples whose gradient vanished (no point)
  int discarded = 0;         ///< candidates inside a neighbour's sphere and not rescued, or
                             ///< missing the slope test (max_slope_miss)
  int rescued = 0;  ///< points kept thanks to a tet gradient (+FN), sliding over the sphere or
                    ///< a power vertex

  int size() const { return int(samples.size()); }
};

/// |value| of each point's sample (`values`: the samples' values, as `cp.samples` index them): how
/// deep each point lies, which the projection and the cells' vertices weigh by.
Eigen::VectorXd contact_depths(const ContactPoints& cp, const Eigen::VectorXd& values);

/// True if c lies inside the sphere of a triangulation neighbour of sample i (see
/// ContactPointOptions::tie_tolerance). Because c lies on sample i's own sphere, testing the
/// regular triangulation's neighbours is the exact power-cell test.
bool inside_neighbour_sphere(const PointMatrix& points, const Eigen::VectorXd& values,
                             const Triangulation& triangulation, int i, const Eigen::Vector3d& c,
                             double tie_tolerance);

/// GCP contact points from per-sample `gradients` (n x 3), filtered on `triangulation` (the
/// regular triangulation for the exact test). With `only` (n flags), just the flagged samples
/// are considered and counted.
ContactPoints gradient_contact_points(const PointMatrix& points, const Eigen::VectorXd& values,
                                      const PointMatrix& gradients,
                                      const Triangulation& triangulation,
                                      const ContactPointOptions& options = {},
                                      const std::vector<char>* only = nullptr);

/// Ground-truth contact points (GTCP): the exact closest surface point of every sample, with the
/// exact gradient as normal. No filter: they all lie on the surface.
/// With `only` (n flags), just the flagged samples.
ContactPoints exact_contact_points(const PointMatrix& points, const AnalyticShape& shape,
                                   const std::vector<char>* only = nullptr);

}  // namespace sdfcontour
