// Internal: the quadric a merged vertex minimises (adaptivity), and each vertex's first one.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// Sum over planes (n, d) of w (n.x + d)^2 = x^T A x + 2 b.x + c.
struct PlaneQuadric {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double c = 0;

  void add_plane(const Eigen::Vector3d& n, const Eigen::Vector3d& p, double w) {
    const double d = -n.dot(p);
    A += w * n * n.transpose();
    b += w * d * n;
    c += w * d * d;
  }
  PlaneQuadric operator+(const PlaneQuadric& o) const {
    PlaneQuadric q;
    q.A = A + o.A, q.b = b + o.b, q.c = c + o.c;
    return q;
  }
  double at(const Eigen::Vector3d& x) const {
    return std::max(0.0, x.dot(A * x) + 2 * b.dot(x) + c);
  }
  // The minimiser nearest `centre` along the directions the planes leave free (eigenvalues
  // under kFree of the largest): a plane keeps its vertex, a crease or corner draws it. Only
  // directions that no curvature fixes are left free: with 1e-3, merged vertices slid along
  // gently curved regions (bunny 128^3, TOL 0.1: L1 1.28x TOL 0's against 1.13x with 1e-6).
  Eigen::Vector3d minimiser(const Eigen::Vector3d& centre) const {
    constexpr double kFree = 1e-6;
    // Where every direction is fixed by a clear margin (most merges on a curved surface), the
    // minimiser is A's solve; the eigenvalues alone, in closed form, tell. Closed-form
    // eigenvectors of a nearly flat region's quadric are not accurate enough: the built-in box
    // at 32^3, TOL 0.25, merged to 82 triangles with them against 72.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> values;
    values.computeDirect(A, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d approximate = values.eigenvalues();
    if (approximate[0] > 2 * kFree * approximate[2])
      return centre + A.ldlt().solve(Eigen::Vector3d(-(A * centre + b)));
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(A);
    const Eigen::Vector3d lambda = eig.eigenvalues();
    const Eigen::Matrix3d U = eig.eigenvectors();
    const Eigen::Vector3d r = -(A * centre + b);
    Eigen::Vector3d x = centre;
    for (int j = 0; j < 3; ++j)
      if (lambda[j] > kFree * lambda[2] && lambda[j] > 0)
        x += U.col(j) * (U.col(j).dot(r) / lambda[j]);
    return x;
  }
};

// A merged region's two quadrics: its contact points' tangent planes and its triangles' planes.
// The points are closer to the surface than the mesh, but their planes are not exact: each
// adds a residual of its own (noise, a normal that is a few tenths of a degree off) which grows
// with the region. So the cost counts each point at a quarter of its weight, and a
// merged vertex goes to the points' and triangles' minimiser only while its region holds a few
// points, to the triangles' alone beyond. Measured at 256^3 against CGAL's Garland-Heckbert
// decimation at the same triangle count (L1 over TOL 0's, docs/adaptivity.md): with both at
// full weight everywhere, penguin 20.3x fewer at 1.119 (GH 1.019), blub 10.9x at 1.117 (GH
// 1.053); with this split, penguin 16.3x at 1.020 (GH 1.024), blub 13.5x at 1.046 (GH 1.062),
// armadillo 6.4x at 1.052 (GH 1.067). The triangles' planes alone (the mesh's own, as GH's)
// lose the points' pull onto the surface: penguin 17.2x at 1.037.
struct MergeQuadric {
  PlaneQuadric points, faces;
  /// The region holds a corner that its contact points share exactly (as a box's): the merged
  /// vertex stays on it, and no merge joins two such corners.
  bool pinned = false;

  static constexpr double kPointCostWeight = 0.25;
  static constexpr double kPointPlacementLimit = 4;  // points a region may hold to place by them

  MergeQuadric operator+(const MergeQuadric& o) const {
    return {points + o.points, faces + o.faces, pinned || o.pinned};
  }
  // The region's summed squared plane distances at x (the cost TOL bounds).
  double at(const Eigen::Vector3d& x) const {
    return faces.at(x) + kPointCostWeight * points.at(x);
  }
  // Where the merged vertex goes (see PlaneQuadric::minimiser); points.A's trace counts them.
  Eigen::Vector3d minimiser(const Eigen::Vector3d& centre) const {
    if (points.A.trace() <= kPointPlacementLimit) return (points + faces).minimiser(centre);
    return faces.minimiser(centre);
  }
};

/// The quadric of each vertex of `mesh`: the tangent planes of the `points` (n x 3, unit
/// `normals` n x 3) nearest it within spacing `h`, and its triangles' own planes, weighed by area
/// over h^2 (a point stands for about h^2 of surface). A vertex on which three or more points
/// lie (to 1e-9 h) with normals that span every direction is pinned: a corner.
std::vector<MergeQuadric> vertex_quadrics(const Mesh& mesh, const PointMatrix& points,
                                          const PointMatrix& normals, double h);

}  // namespace sdfcontour::detail
