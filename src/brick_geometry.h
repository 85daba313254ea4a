// Exact geometry for the bricks' certificates (internal). A brick's sample keeps its global star
// if no sample outside the brick conflicts with a tetrahedron of its star: an orthosphere that
// stays inside the brick, and, on the brick's convex hull, hull facets that are global ones.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "sdfcontour/samples.h"

namespace sdfcontour {

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
