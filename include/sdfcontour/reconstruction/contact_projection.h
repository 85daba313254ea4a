// Projection onto the contact points: a reconstructed mesh moved onto a local fit of the points.
//
// The screened Poisson surface is smooth: it passes near the contact points but, where the
// normals it is given turn (a curved surface sampled every spacing), it cuts the corners, and it
// rounds edges and flattens poles by up to ~0.01 spacing on exact distances. The contact points
// themselves are more accurate than that: an error of angle t in a sample's gradient moves its
// point along the sample's sphere, which touches the surface, so off the surface by only
// ~|value| t^2 / 2. Each vertex here moves along its normal onto a weighted least-squares
// quadric (a height field over the vertex's tangent plane) through the contact points near it
// whose normals agree with its own (the builtin sphere at 64^3: largest error 0.008 h ->
// 0.0004 h; docs/projection.md).
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

namespace detail {
class PointCubes;
struct VertexTriangles;
struct ChordOffsets;
}  // namespace detail

struct ContactProjectionOptions {
  /// Radius of the neighbourhood fitted around each vertex, in spacings (Gaussian weights of
  /// standard deviation radius / sqrt(8) over the tangent plane).
  double radius = 2;
  /// A vertex moves at most this many spacings; a larger correction is not applied (the fit then
  /// meets a feature it cannot represent: an edge, a thin part, the other side).
  double max_move = 0.25;
  /// Points whose normal is more than acos(normal_agreement) from the vertex's are not fitted.
  double normal_agreement = 0.8;
  /// Fewer agreeing points than this within the radius leave the vertex where it is.
  int min_points = 12;
  /// A point from a sample |value| away weighs 1 / (1 + (|value| / (depth_scale spacings))^2):
  /// far samples' points are less accurate. 0: every point weighs the same.
  double depth_scale = 0;
  /// A fit whose height is this much less certain than a mean of its points' (the intercept's
  /// variance factor, (M^-1)_00 times the weights' sum: ~1 for points spread evenly around the
  /// vertex) extrapolates from one side: the vertex stays.
  double max_variance_factor = 8;
  /// Where the points' weighted RMS distance from the fitted quadric exceeds this many spacings,
  /// they are no smooth surface (an edge, facets finer than the radius, a thin part's two sides):
  /// the vertex stays. 0: no limit.
  double max_residual = 0.005;
  /// Rounds that refit with each point's weight divided by 1 + (its miss / robust_scale
  /// spacings)^2, so that a few points off the surface (where spheres meet in a gap short of a
  /// saddle) do not bend the fit. 0: one weighted least-squares fit.
  int robust_rounds = 0;
  double robust_scale = 0.02;
  /// Degrees: each fit divides a point's weight by 1 + (t / normal_turn_scale)^2, t the turn
  /// between its normal and the fit's normal where it lies (the vertex's normal in the first
  /// fit), measured by its chord: 2 sin(t / 2) against 2 sin(normal_turn_scale / 2). Points whose
  /// normal disagrees with their place (gradients blended across an edge or a medial axis, which
  /// land a few hundredths of a spacing inside a face) then lose their pull on curved and flat
  /// regions alike (after Poisson: shared meshes' L1 0.340x -> 0.337x MC's at 64^3, `bench/local.py
  /// --res 64 --methods mc,gcp-poisson`). 0: off.
  double normal_turn_scale = 5;
  /// Where the fit within radius gives no reliable height although at least min_points points
  /// there agree with the vertex's normal (points on lines further apart than the radius, as
  /// grid-aligned flats give), fit again within this many spacings; 0: no second fit (the vertex
  /// stays).
  double wide_radius = 0;
  /// Each vertex goes to the fit's height plus its chord offset: minus the mean, over its
  /// triangles, of the fit's quadratic part over their edges / 12, which is how far a flat
  /// triangle with its corners on the fitted surface lies below it on average. The mesh then
  /// straddles a curved surface instead of lying under it on the convex side.
  bool chord_offset = false;
  /// Where the points lie on two planes far closer than on the quadric (a crease between two
  /// facets, which the quadric rounds off: a polyhedral mesh's SDF has them everywhere, and at
  /// fine grids most of the error lies next to them), the vertex goes onto the crease instead:
  /// the lower plane on a ridge, the higher in a valley, without a chord offset.
  bool crease_planes = false;
  /// Called with (vertices done, vertices) as the fit goes, from any thread, one call at a time.
  std::function<void(long, long)> progress;
};

struct ContactProjectionStats {
  long vertices_moved = 0;  ///< vertices the fit moved
  double largest_move = 0;  ///< the longest move, in the mesh's units
};

/// The local reconstruction's projection options: radius 1.25 spacings (2 where that gives no
/// height), no residual limit, two robust rounds at 0.03 spacings (each also weighing the points
/// by their normals' turn from the fit's, as every fit does), chord offsets, crease planes
/// (pipeline.h, ContourOptions::local_projection, says why).
inline ContactProjectionOptions local_projection_options() {
  ContactProjectionOptions p;
  p.radius = 1.25;
  p.wide_radius = 2;
  p.max_residual = 0;
  p.robust_rounds = 2;
  p.robust_scale = 0.03;
  p.chord_offset = true;
  p.crease_planes = true;
  return p;
}

/// Moves the vertices of `mesh` (in place) along their area-weighted normals onto the quadric
/// fitted to the contact points `points` (k x 3) with unit outward `normals` (k x 3) near each;
/// `depths` (k, or empty) are the |value|s of the points' samples, for options.depth_scale.
/// Every vertex is fitted from the input positions, so the result does not depend on the order
/// or the thread count. `spacing` (> 0) is the samples' spacing, the unit of the options' lengths.
/// Throws Error for mismatched sizes, non-finite input or options out of range.
/// With `fixed` (one flag per vertex), the flagged vertices stay where they are (a sharp edge's
/// vertices, which the smooth fit would round).
ContactProjectionStats project_to_contact_points(Mesh& mesh, const PointMatrix& points,
                                                 const PointMatrix& normals,
                                                 const Eigen::VectorXd& depths, double spacing,
                                                 const ContactProjectionOptions& options = {},
                                                 const std::vector<char>* fixed = nullptr);

/// project_to_contact_points with the points indexed once, for several meshes (or a mesh again
/// after a split adds vertices): the same results, without indexing the points again. The points
/// and normals are read by project() and must outlive the projector, unchanged (temporaries are
/// refused); the depths are copied. Throws as that function does, when made.
class ContactProjector {
 public:
  ContactProjector(const PointMatrix& points, const PointMatrix& normals,
                   const Eigen::VectorXd& depths, double spacing,
                   const ContactProjectionOptions& options = {});
  ContactProjector(PointMatrix&&, const PointMatrix&, const Eigen::VectorXd&, double,
                   const ContactProjectionOptions& = {}) = delete;
  ContactProjector(const PointMatrix&, PointMatrix&&, const Eigen::VectorXd&, double,
                   const ContactProjectionOptions& = {}) = delete;
  ~ContactProjector();
  ContactProjector(const ContactProjector&) = delete;
  ContactProjector& operator=(const ContactProjector&) = delete;

  /// project_to_contact_points(mesh, points, normals, depths, spacing, options, fixed). With
  /// `chords` (internal: the local reconstruction's), each vertex it fits where the surface is
  /// smooth at the spacing's scale has its chord offset recorded there (sized to the mesh's
  /// vertices if it is not already; other entries are left as they are).
  ContactProjectionStats project(Mesh& mesh, const std::vector<char>* fixed = nullptr,
                                 detail::ChordOffsets* chords = nullptr) const;
  /// The same with `around`, the mesh's triangles around each vertex that is not fixed, made by
  /// the caller (who reads them again).
  ContactProjectionStats project(Mesh& mesh, const std::vector<char>* fixed,
                                 const detail::VertexTriangles& around,
                                 detail::ChordOffsets* chords = nullptr) const;
  /// The samples' spacing it was made with.
  double spacing() const { return spacing_; }

 private:
  const PointMatrix& points_;
  const PointMatrix& normals_;
  Eigen::VectorXd depths_;
  double spacing_;
  ContactProjectionOptions options_;
  std::unique_ptr<detail::PointCubes> cubes_;  // null without points
};

}  // namespace sdfcontour
