// Internal: small geometric quantities of a triangle mesh that several stages read.
#pragma once

#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

/// Each vertex's triangles in ascending order: those of vertex v are
/// triangles[offsets[v]] .. triangles[offsets[v + 1] - 1]. Sums over them in this order are the
/// sums of a serial pass over the triangles, bit for bit, whatever the threads.
struct VertexTriangles {
  std::vector<int> offsets;  ///< vertices + 1 entries
  std::vector<int> triangles;
  explicit VertexTriangles(const Mesh& mesh);
};

/// Area-weighted vertex normals (n x 3, unit; zero where the triangles around cancel or there are
/// none); each vertex's sum in its triangles' order, so the same bits for any thread count.
PointMatrix vertex_normals(const Mesh& mesh);
PointMatrix vertex_normals(const Mesh& mesh, const VertexTriangles& around);

/// Barycentric coordinates of q (in the plane of triangle t) in triangle t; zero for a degenerate
/// triangle.
Eigen::Vector3d barycentric(const Mesh& mesh, Eigen::Index t, const Eigen::Vector3d& q);

}  // namespace sdfcontour::detail
