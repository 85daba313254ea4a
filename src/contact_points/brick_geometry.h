// The bricks' certificates (internal). A brick's sample keeps its global star if no sample
// outside the brick conflicts with a cell of its star: every orthosphere stays inside the
// brick, and, on the brick's convex hull, every hull facet is a global one.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour {

class BrickShell;

/// An axis-aligned box: a brick with its halo.
struct BrickBox {
  Eigen::Vector3d min, max;
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  bool contains(const BrickBox& b) const { return contains(b.min) && contains(b.max); }
  // Distance from p (inside) to the box's outside; 0 outside.
  double depth(const Eigen::Vector3d& p) const {
    if (!contains(p)) return 0;
    return std::min((p - min).minCoeff(), (max - p).minCoeff());
  }
};

/// True if the ball about c of squared radius reach2 stays `margin` inside `box`; else `need`
/// grows to hold it (unless it is not finite: the caller widens the box then).
bool sphere_inside(const Eigen::Vector3d& c, double reach2, const BrickBox& box, double margin,
                   BrickBox& need);

/// True if no sample outside `box` conflicts with (has a negative power product with) the
/// orthosphere of the tet with sample rows v[0..3] (positions p, weights values²): either the
/// orthosphere grown by `max_weight` (the largest outside weight) stays `margin` inside `box`,
/// or it stays inside the `shell`'s outer box (if any) and none of the shell's samples conflicts
/// with it. Otherwise `need` grows to hold the grown sphere (or, for an exactly flat tet, by
/// nothing). Tets too flat for doubles are solved exactly.
bool orthosphere_certified(const PointMatrix& p, const Eigen::VectorXd& values, const int* v,
                           const BrickBox& box, const BrickShell* shell, double max_weight,
                           double margin, BrickBox& need);

/// The same for the power circle of the triangle v[0..2] in its plane (a facet in a flat face
/// of the hull: only samples on that plane can conflict with its infinite cell).
bool power_circle_inside(const PointMatrix& p, const Eigen::VectorXd& values, const int* v,
                         const BrickBox& box, double max_weight, double margin, BrickBox& need);

/// Local row r of `tri` (the triangulation of `ls`) is on the local hull: true if the facets of
/// its star there (in one of its finite tets only) are facets of the global hull, whose vertices
/// are `hull`, so that its infinite cells are global ones too. A facet in a flat face of the
/// global hull also needs its power circle, grown by `max_weight`, inside `box` (else `need`
/// grows to hold it).
bool hull_facets_global(const Samples& ls, const Triangulation& tri, int r,
                        const std::vector<Eigen::Vector3d>& hull, double max_weight, double margin,
                        const BrickBox& box, BrickBox& need);

/// The vertices of the convex hull of `points` (n x 3), found brick by brick in parallel: the
/// hull of every bucket's own hull vertices. `buckets[b]` lists the rows of bucket b.
std::vector<Eigen::Vector3d> convex_hull_vertices(const PointMatrix& points,
                                                  const std::vector<std::vector<int>>& buckets);

/// Where the facet a, b, c of a local convex hull stands in the global hull, whose vertices are
/// `hull`; `inner` is a point strictly on the local hull's side. Exact orientation predicates.
enum class HullFacet {
  Global,        ///< no point lies beyond or on its plane but a, b, c: a global hull facet
  InGlobalFace,  ///< none beyond, others on its plane: part of a flat face of the global hull
                 ///< (a grid's side); global if no point on the plane outside the brick is in
                 ///< the facet's power circle
  NotGlobal,     ///< a point lies beyond (or the facet is flat)
};
HullFacet classify_hull_facet(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& inner,
                              const std::vector<Eigen::Vector3d>& hull);

/// The orthocentre (weighted circumcentre) of the tetrahedron a, b, c, d with weights w, in
/// exact arithmetic, rounded: for tetrahedra too flat for a floating-point solve (grid samples
/// on one diagonal plane, made a tetrahedron by their coordinates' rounding), whose orthosphere
/// the triangulation's exact predicates still see as a small sphere near the surface.
/// False if the four points are exactly coplanar.
bool exact_orthocentre(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d, const Eigen::Vector4d& w, Eigen::Vector3d& centre);

}  // namespace sdfcontour
