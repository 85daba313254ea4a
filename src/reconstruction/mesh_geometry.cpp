#include "reconstruction/mesh_geometry.h"

#include <tbb/parallel_for.h>

#include <limits>

namespace sdfcontour::detail {

VertexTriangles::VertexTriangles(const Mesh& mesh) {
  if (mesh.vertices.rows() >= std::numeric_limits<int>::max() ||
      3 * mesh.triangles.rows() >= std::numeric_limits<int>::max())
    throw Error("too many vertices or triangles for one mesh piece (2^31 corners)");
  const TriangleMatrix& F = mesh.triangles;
  offsets.assign(std::size_t(mesh.vertices.rows()) + 1, 0);
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int c = 0; c < 3; ++c) ++offsets[std::size_t(F(t, c)) + 1];
  for (std::size_t v = 1; v < offsets.size(); ++v) offsets[v] += offsets[v - 1];
  triangles.resize(std::size_t(offsets.back()));
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int c = 0; c < 3; ++c) triangles[std::size_t(fill[std::size_t(F(t, c))]++)] = int(t);
}

PointMatrix vertex_normals(const Mesh& mesh) {
  return vertex_normals(mesh, VertexTriangles(mesh));
}

PointMatrix vertex_normals(const Mesh& mesh, const VertexTriangles& around) {
  PointMatrix N(mesh.vertices.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), N.rows(), [&](Eigen::Index v) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (int e = around.offsets[std::size_t(v)]; e < around.offsets[std::size_t(v) + 1]; ++e) {
      const Eigen::Index t = around.triangles[std::size_t(e)];
      const Eigen::RowVector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                               b = mesh.vertices.row(mesh.triangles(t, 1)),
                               c = mesh.vertices.row(mesh.triangles(t, 2));
      sum += (b - a).cross(c - a);
    }
    const double len = sum.norm();
    N.row(v) = len > 0 ? Eigen::RowVector3d(sum / len) : Eigen::RowVector3d::Zero();
  });
  return N;
}

Eigen::Vector3d barycentric(const Mesh& mesh, Eigen::Index t, const Eigen::Vector3d& q) {
  const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                        b = mesh.vertices.row(mesh.triangles(t, 1)),
                        c = mesh.vertices.row(mesh.triangles(t, 2));
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = q - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = d.dot(e0),
               d21 = d.dot(e1), den = d00 * d11 - d01 * d01;
  if (!(den > 0)) return Eigen::Vector3d(0, 0, 0);
  const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  return Eigen::Vector3d(1 - v - w, v, w);
}

}  // namespace sdfcontour::detail
