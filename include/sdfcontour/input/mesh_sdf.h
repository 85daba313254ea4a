// The exact signed distance to a closed triangle mesh: closest points from a CGAL AABB tree, the
// sign from the mesh's winding number (exact ray crossings, counted with their orientation).
#pragma once

#include <memory>
#include <optional>

#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

/// Throws Error unless `mesh` has triangles, coordinates within kLargestCoordinate, and is closed,
/// consistently oriented and free of self-intersections (overlapping parts have no single inside;
/// merge them first). Zero-area triangles are accepted.
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
  /// Non-zero winding number: inside where the mesh's surfaces wind around p at least once
  /// (overlapping parts and nested shells counted by orientation, not by parity of crossings).
  bool inside(const Eigen::Vector3d& p) const;
  /// Exits minus entries of the ray from p along `direction` through the mesh's triangles; empty
  /// if the ray grazes an edge, a vertex or a triangle's plane (another direction is needed).
  std::optional<int> winding_along(const Eigen::Vector3d& p,
                                   const Eigen::Vector3d& direction) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sdfcontour
