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

/// The symmetric Hausdorff distance between two meshes, estimated from each mesh's vertices plus
/// `samples` area-uniform points, each measured exactly against the other mesh.
double hausdorff_distance(const Mesh& a, const Mesh& b, std::size_t samples = 100000,
                          std::uint64_t seed = 1);

}  // namespace sdfcontour
