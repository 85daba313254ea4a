// Internal: the parts of sphere carving shared by its vertex phase (sphere_carving.cpp) and its
// triangle phase (carving_triangles.cpp).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "sdfcontour/reconstruction/sphere_carving.h"

namespace sdfcontour::detail {

class WorkCounter;

/// Throws Error ("`what`: ...") unless points (n x 3) and values (n) match and are finite and the
/// spacing is positive and finite: the samples whose balls carving and side repair keep clear.
void check_ball_samples(const char* what, const PointMatrix& points, const Eigen::VectorXd& values,
                        double spacing);

/// The triangles around each vertex: those of vertex v are triangles[offsets[v] .. offsets[v+1]).
/// Built once per mesh (carving moves vertices, never triangles). With `skip`, the vertices it
/// sets get none (a projection that fits a few vertices reads only theirs).
struct VertexTriangles {
  std::vector<int> offsets, triangles;
  explicit VertexTriangles(const Mesh& mesh, const std::vector<char>* skip = nullptr);
};

/// Scales each vertex's move in `moves` (per vertex, factor[v] times its row: 1, halved, then 0)
/// until no triangle's normal turns by more than options.max_turn_degrees; returns the vertices
/// held back.
long hold_back_turning_triangles(const Mesh& mesh, const PointMatrix& moves,
                                 std::vector<double>& factor, const CarvingOptions& options);

/// The samples whose side of the mesh is wrong or whose ball holds part of a triangle, and the
/// moves that put each of them outside the mesh's nearest feature.
struct SideCheck {
  long violations = 0;       ///< samples on the wrong side or with a triangle inside their ball
  long wrong_side = 0;       ///< of those, the samples on the wrong side
  PointMatrix moves;         ///< per vertex (rows of mesh.vertices); zero where none is asked
  std::vector<int> nearest;  ///< per checked sample, its nearest triangle
  double farthest = 0;       ///< the largest distance from a checked sample to its nearest point
  std::vector<char> failed;  ///< per checked sample, whether it violates
};

/// Checks the samples `which` (indices into points / values; `around`: the mesh's) against the
/// mesh's nearest point: a sample with value v must lie on the side of sign(v) of it, at least |v|
/// away. For each that does not, the vertices of the nearest feature (triangle, edge or vertex) are
/// asked to move along the feature's (pseudo)normal so that it would; a vertex asked by several
/// samples takes a wrong-side sample's move before a ball's, then the longest (ties: the lower
/// sample). Thread-count independent. A ball counts as cut only where the mesh reaches more than
/// `slack` into it; a sample whose move would be longer than `longest` counts but moves nothing.
/// `among` (optional): the triangles to look for the nearest among (default: all).
SideCheck check_sample_sides(const Mesh& mesh, const VertexTriangles& around,
                             const PointMatrix& points, const Eigen::VectorXd& values,
                             const std::vector<int>& which, double slack, double longest,
                             const std::vector<int>* among = nullptr);

/// The point of the triangles `among` nearest to p, the vertices of the feature (triangle, edge
/// or vertex) it lies on, the feature's outward (pseudo)normal, and p's height above it along
/// that normal (its sign is p's side of the mesh). triangle < 0 if `among` is empty.
struct NearestFeature {
  int triangle = -1;
  std::vector<int> vertices;
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
  double height = 0;
};
NearestFeature nearest_feature(const Mesh& mesh, const VertexTriangles& around,
                               const Eigen::Vector3d& p, const std::vector<int>& among);

/// The samples with |value| <= reach (ascending) whose ball of radius ball * |value| + grow meets
/// a triangle around one of `vertices` (ball 1: the sample's own ball, grown; 0: a ball of radius
/// `grow` about the sample's point).
std::vector<int> samples_near_vertices(const Mesh& mesh, const VertexTriangles& around,
                                       const std::vector<int>& vertices, const PointMatrix& points,
                                       const Eigen::VectorXd& values, double reach, double grow,
                                       double ball);

/// The triangles within `rings` rings (triangles sharing a vertex) of `seeds` (ascending; entries
/// < 0 are skipped).
std::vector<int> triangles_around(const Mesh& mesh, const VertexTriangles& around,
                                  const std::vector<int>& seeds, int rings);

/// For each vertex of `which` inside at least one ball (centre points.row(i), radius
/// |values[i]|), the displacement onto the sphere of the ball it enters deepest (ties: the lower
/// sample); zero elsewhere. Each vertex's move depends on its position and the balls alone.
PointMatrix deepest_pushes(const PointMatrix& V, const std::vector<int>& which,
                           const PointMatrix& points, const Eigen::VectorXd& values, double spacing,
                           WorkCounter* samples_done = nullptr);

class Lattice;

/// The same for the balls on a grid's lattice (`balls`: its samples and their values; with `use`,
/// one flag per sample, the flagged alone): each box of vertices reads the balls that meet it,
/// gathered once, in place of each ball reading the vertices near it. The same pushes, bit for
/// bit.
/// With `allowance` (per vertex, a length), a vertex counts as inside a ball only when deeper than
/// its allowance, and goes back only to that depth.
PointMatrix deepest_pushes(const PointMatrix& V, const std::vector<int>& which,
                           const Lattice& balls, const std::vector<char>* use, double spacing,
                           const std::vector<double>* allowance = nullptr);

/// Up to `passes` rounds of each vertex of V pushed onto the sphere of the ball it enters
/// deepest (the balls on a grid's lattice, `use` as in deepest_pushes), every vertex on its own
/// (no triangle checks): the result of a vertex depends on its position and the balls near it
/// alone, as bricks need. A push that would take a vertex more than `max_move` spacings from
/// where it started is not made (a long one meets a part the mesh lacks, or the other side of a
/// thin part), which also bounds how far apart two triangles that come to cross can have started.
/// `allowance` as in deepest_pushes.
void carve_vertices_alone(PointMatrix& V, const Lattice& balls, const std::vector<char>* use,
                          double spacing, int passes, double max_move,
                          const std::vector<char>* fixed = nullptr,
                          const std::vector<double>* allowance = nullptr);

}  // namespace sdfcontour::detail
