// A convex polytope cut from a box by half-spaces, with the planes that make each vertex: a
// sample's power cell among the spheres near it (lattice_contact_points.cpp), whose vertices on
// the sample's own sphere are where four spheres meet.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

namespace sdfcontour::detail {

class ConvexCell {
 public:
  /// The box [lo, hi]; its six faces are planes -1 to -6.
  ConvexCell(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) { reset(lo, hi); }
  ConvexCell() = default;
  /// The box again, the storage kept (one cell per thread, many samples).
  void reset(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);

  /// Keeps the part where normal . x <= offset (`normal` of unit length); `id` >= 0 names the
  /// plane. Points within `tolerance` of the plane count as on it.
  void clip(const Eigen::Vector3d& normal, double offset, int id, double tolerance);

  bool empty() const { return vertices_.empty(); }

  struct Vertex {
    Eigen::Vector3d point;
    std::array<int, 3> planes;  ///< three of the planes through it (ascending)
  };
  const std::vector<Vertex>& vertices() const { return vertices_; }

 private:
  std::vector<Vertex> vertices_;
  Eigen::Vector3d lo_, hi_;  // the vertices' bounding box: planes that miss it cost no more
  // Faces as vertex cycles, one after another: face f is face_vertices_[face_start_[f] ..
  // face_start_[f + 1]), on plane face_plane_[f].
  std::vector<int> face_vertices_, face_start_, face_plane_;
  // Scratch of clip(), kept between calls.
  std::vector<double> d_;
  std::vector<int> index_, cap_, new_vertices_, new_start_, new_plane_;
  std::vector<Vertex> kept_;
  std::vector<std::array<int, 3>> cut_;  // (low, high, new vertex) of each cut edge
  std::vector<std::pair<double, int>> order_;
};

}  // namespace sdfcontour::detail
