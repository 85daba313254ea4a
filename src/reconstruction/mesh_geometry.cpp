#include "reconstruction/mesh_geometry.h"

#include <tbb/parallel_for.h>

#include "reconstruction/carving_internal.h"

namespace sdfcontour::detail {

PointMatrix vertex_normals(const Mesh& mesh) {
  PointMatrix N = PointMatrix::Zero(mesh.vertices.rows(), 3);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const Eigen::RowVector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                             b = mesh.vertices.row(mesh.triangles(t, 1)),
                             c = mesh.vertices.row(mesh.triangles(t, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) N.row(mesh.triangles(t, k)) += n;
  }
  for (Eigen::Index v = 0; v < N.rows(); ++v) {
    const double len = N.row(v).norm();
    N.row(v) = len > 0 ? Eigen::RowVector3d(N.row(v) / len) : Eigen::RowVector3d::Zero();
  }
  return N;
}

Eigen::RowVector3d unit_vertex_normal(const Mesh& mesh, const VertexTriangles& around,
                                      Eigen::Index v) {
  Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
  for (int o = around.offsets[std::size_t(v)]; o < around.offsets[std::size_t(v) + 1]; ++o) {
    const int t = around.triangles[std::size_t(o)];
    const Eigen::RowVector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                             b = mesh.vertices.row(mesh.triangles(t, 1)),
                             c = mesh.vertices.row(mesh.triangles(t, 2));
    sum += (b - a).cross(c - a);
  }
  const double len = sum.norm();
  return len > 0 ? Eigen::RowVector3d(sum / len) : Eigen::RowVector3d::Zero();
}

PointMatrix vertex_normals(const Mesh& mesh, const VertexTriangles& around) {
  PointMatrix N(mesh.vertices.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(),
                    [&](Eigen::Index v) { N.row(v) = unit_vertex_normal(mesh, around, v); });
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
