// The exact signed distance to a closed triangle mesh: closest points from a CGAL AABB tree, the
// sign from CGAL's robust inside test.
#pragma once

#include <memory>

#include "sdfcontour/builtin_shapes.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// Throws Error unless `mesh` has triangles and is closed and consistently oriented.
void require_closed_mesh(const Mesh& mesh, const std::string& what);

/// Signed distance to a closed, consistently oriented mesh (negative inside). Queries are
/// thread-safe. An AnalyticShape, so GTCP and the samplers work on meshes as on built-ins.
class MeshSdf : public AnalyticShape {
 public:
  /// Throws Error if the mesh is not closed (see require_closed_mesh).
  explicit MeshSdf(const Mesh& mesh);
  ~MeshSdf() override;
  MeshSdf(const MeshSdf&) = delete;
  MeshSdf& operator=(const MeshSdf&) = delete;

  double distance(const Eigen::Vector3d& p) const override;
  /// Unit vector from the closest surface point towards p, outward (the SDF's gradient); for p
  /// on the surface, the closest triangle's normal.
  Eigen::Vector3d gradient(const Eigen::Vector3d& p) const override;
  /// Unsigned distance, closest point and the index of its triangle.
  double unsigned_distance(const Eigen::Vector3d& p, Eigen::Vector3d* closest = nullptr,
                           int* triangle = nullptr) const;
  /// Outward unit normal of triangle t.
  Eigen::Vector3d triangle_normal(int t) const;
  bool inside(const Eigen::Vector3d& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sdfcontour
