// The nearest triangle of a mesh to many query points (and whether any meets a ball), with an
// index built in parallel.
#pragma once

#include <memory>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

/// Nearest-triangle queries over a subset of a mesh's triangles. Where the triangles' sizes are
/// alike (the local reconstruction's meshes), a uniform grid of cells as large as the largest
/// triangle's box, each listing the triangles that meet it: a query reads the cells around its
/// point, then twice as far until every unread cell lies farther than the nearest triangle found.
/// Elsewhere CGAL's AABB trees, which build in one thread (a second or two at a million
/// triangles): the triangles are cut into spatially compact chunks (Morton order of their
/// centroids, a chunk size set by the count alone, so the result does not depend on the thread
/// count), one tree per chunk, built in parallel; a query visits the chunks by the distance to
/// their boxes and stops at the first box farther than the nearest triangle found. Either answer
/// is exact.
class NearestTriangles {
 public:
  /// mesh: the triangles' vertices and indices, read by the queries (it must outlive the index,
  /// unchanged); among: the triangles searched (all if null).
  /// many_queries: whether each chunk also builds CGAL's kd-tree of hints (pays off over
  /// thousands of queries).
  NearestTriangles(const Mesh& mesh, const std::vector<int>* among, bool many_queries);
  ~NearestTriangles();
  NearestTriangles(const NearestTriangles&) = delete;
  NearestTriangles& operator=(const NearestTriangles&) = delete;

  struct Hit {
    int triangle = -1;  ///< the mesh's triangle index; -1 if there are no triangles
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< the nearest point on it
  };
  /// The nearest triangle to p (ties: the grid's lowest index; the trees' lower chunk, then
  /// CGAL's choice within one); safe to call from many threads at once.
  Hit closest(const Eigen::Vector3d& p) const;

  /// Whether any of the triangles meets the closed ball of centre c and radius `radius`; safe to
  /// call from many threads at once.
  bool meets_ball(const Eigen::Vector3d& c, double radius) const;

  bool empty() const { return chunks_.empty() && !grid_; }

 private:
  struct Chunk;
  struct Grid;
  std::vector<std::unique_ptr<Chunk>> chunks_;
  std::unique_ptr<Grid> grid_;
};

}  // namespace sdfcontour::detail
