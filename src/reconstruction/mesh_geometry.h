// Internal: small geometric quantities of a triangle mesh that several stages read.
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

/// Area-weighted vertex normals (n x 3, unit; zero where the triangles around cancel or there are
/// none). Serial: the sums' order, hence the result, is fixed.
PointMatrix vertex_normals(const Mesh& mesh);

struct VertexTriangles;

/// The same, bit for bit, in parallel: each vertex sums its triangles (`around`, the mesh's) in
/// ascending order, as the serial sweep does.
PointMatrix vertex_normals(const Mesh& mesh, const VertexTriangles& around);

/// Vertex v's row of vertex_normals(mesh, around), alone.
Eigen::RowVector3d unit_vertex_normal(const Mesh& mesh, const VertexTriangles& around,
                                      Eigen::Index v);

/// Barycentric coordinates of q (in the plane of triangle t) in triangle t; zero for a degenerate
/// triangle.
Eigen::Vector3d barycentric(const Mesh& mesh, Eigen::Index t, const Eigen::Vector3d& q);

}  // namespace sdfcontour::detail
