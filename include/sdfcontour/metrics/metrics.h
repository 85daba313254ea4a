// Distances between surfaces: exact point-to-triangle distances (CGAL AABB tree) from points
// sampled uniformly by area.
#pragma once

#include <cstdint>
#include <memory>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// `count` points uniformly distributed by area on `mesh`; deterministic in `seed`.
PointMatrix sample_surface(const Mesh& mesh, std::size_t count, std::uint64_t seed);

/// Exact unsigned distance from each row of `points` to the closest point of `mesh`'s triangles.
Eigen::VectorXd point_mesh_distances(const PointMatrix& points, const Mesh& mesh);

/// The paper's three distances between meshes a and b, from `samples` area-uniform points on each
/// (plus the vertices, for the maximum), each measured exactly against the other mesh.
struct SurfaceDistances {
  double hausdorff = 0;  ///< L-infinity: max of the two directed maxima
  double l1 = 0;         ///< mean of the two directed mean distances
  double l2 = 0;         ///< mean of the two directed RMS distances
  double mean_ab = 0, mean_ba = 0, rms_ab = 0, rms_ba = 0, max_ab = 0, max_ba = 0;
};
SurfaceDistances surface_distances(const Mesh& a, const Mesh& b, std::size_t samples = 200000,
                                   std::uint64_t seed = 1);

/// The symmetric Hausdorff distance between two meshes, estimated from each mesh's vertices plus
/// `samples` area-uniform points, each measured exactly against the other mesh.
double hausdorff_distance(const Mesh& a, const Mesh& b, std::size_t samples = 100000,
                          std::uint64_t seed = 1);

}  // namespace sdfcontour
