// How well contact points (or any oriented points) sit on a known surface: the distance of each
// point to it and the alignment of each normal with the surface's.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <utility>
#include <vector>

#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/signed_distance.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// Per point i: abs_value[i] = |phi(p_i)| against the reference surface, alignment[i] =
/// (n_i / |n_i|) . (the reference's outward unit normal there), 1 for a perfect normal.
struct ContactPointErrors {
  std::vector<double> abs_value;
  std::vector<double> alignment;
};

/// The reference at a point: (distance to the surface, outward unit normal). Thread-safe.
using SurfaceReference =
    std::function<std::pair<double, Eigen::Vector3d>(const Eigen::Vector3d& point)>;

/// points (n x 3) and normals (n x 3, any non-zero length) against `reference`, in parallel.
ContactPointErrors contact_point_errors(const PointMatrix& points, const PointMatrix& normals,
                                        const SurfaceReference& reference);
/// Against an exact signed distance: |phi(p)| and its gradient.
ContactPointErrors contact_point_errors(const PointMatrix& points, const PointMatrix& normals,
                                        const AnalyticShape& sdf);
/// Against a closed mesh: the distance to it and the normal of the closest triangle.
ContactPointErrors contact_point_errors(const PointMatrix& points, const PointMatrix& normals,
                                        const MeshSdf& mesh);

/// Order statistics of a list of numbers (all 0 for an empty list).
struct Summary {
  double median = 0, mean = 0, p05 = 0, p95 = 0;
};
Summary summarize(const std::vector<double>& values);

}  // namespace sdfcontour
