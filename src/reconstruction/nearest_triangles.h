// The nearest triangle of a mesh to many query points (and whether any meets a ball), with an
// index built in parallel.
#pragma once

#include <memory>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

/// Nearest-triangle queries over a subset of a mesh's triangles. CGAL's AABB tree builds in one
/// thread, which at a million triangles is a second or two of a run that is otherwise parallel:
/// here the triangles are cut into spatially compact chunks (Morton order of their centroids, a
/// chunk size set by the count alone, so the result does not depend on the thread count), one
/// tree per chunk, built in parallel. A query visits the chunks by the distance to their boxes
/// and stops at the first box farther than the nearest triangle found: the answer is exact.
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
  /// The nearest triangle to p (ties: the lower chunk, then CGAL's choice within one); safe to
  /// call from many threads at once.
  Hit closest(const Eigen::Vector3d& p) const;

  /// Whether any of the triangles meets the closed ball of centre c and radius `radius`; safe to
  /// call from many threads at once.
  bool meets_ball(const Eigen::Vector3d& c, double radius) const;

  bool empty() const { return chunks_.empty(); }

 private:
  struct Chunk;
  std::vector<std::unique_ptr<Chunk>> chunks_;
};

}  // namespace sdfcontour::detail
