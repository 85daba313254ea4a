#include "sdfcontour/mesh_transform.h"

namespace sdfcontour {

Mesh normalize_mesh(const Mesh& mesh, double half_extent) {
  if (mesh.vertices.rows() == 0) throw Error("the mesh has no vertices");
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff(),
                           hi = mesh.vertices.colwise().maxCoeff();
  const double longest = (hi - lo).maxCoeff();
  if (!(longest > 0)) throw Error("the mesh has no extent");
  Mesh out = mesh;
  const Eigen::RowVector3d centre = 0.5 * (lo + hi);
  out.vertices = ((mesh.vertices.rowwise() - centre) * (2 * half_extent / longest)).eval();
  return out;
}

}  // namespace sdfcontour
