// The regular (weighted Delaunay) triangulation of SDF samples with weights value^2, or the
// Delaunay triangulation (weights zero), exposed as plain arrays.
#pragma once

#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

enum class TriangulationKind {
  Regular,   ///< weighted Delaunay of (p_i, value_i^2): the power diagram's dual
  Delaunay,  ///< plain Delaunay of the positions
};

struct TriangulationOptions {
  TriangulationKind kind = TriangulationKind::Regular;
  bool parallel = true;  ///< insert points with TBB (the result is the same either way)
};

/// A run of indices inside a compressed row (range-for over it).
struct IndexRun {
  const int* first;
  const int* last;
  const int* begin() const { return first; }
  const int* end() const { return last; }
};

/// A triangulation of n samples. Compressed rows: the neighbours of sample i are
/// neighbour_indices[neighbour_offsets[i] .. neighbour_offsets[i+1]), ascending.
struct Triangulation {
  TetMatrix tets;                      ///< m x 4 finite tetrahedra, positively oriented, sorted
  std::vector<int> neighbour_offsets;  ///< n + 1 offsets into neighbour_indices
  std::vector<int> neighbour_indices;  ///< samples sharing an edge with sample i
  std::vector<int> incident_offsets;   ///< n + 1 offsets into incident_tets
  std::vector<int> incident_tets;      ///< rows of `tets` that contain sample i, ascending
  std::vector<char> hidden;            ///< n flags: 1 if sample i is not a vertex (hidden by
                                       ///< larger spheres, or a duplicate position)
  int hidden_count = 0;
  std::vector<char> on_hull;  ///< n flags: 1 if sample i is a vertex of the convex hull

  int sample_count() const { return int(hidden.size()); }
  /// The samples sharing an edge with sample i, ascending.
  IndexRun neighbours(int i) const { return run(neighbour_offsets, neighbour_indices, i); }
  /// The rows of `tets` that contain sample i, ascending.
  IndexRun incident(int i) const { return run(incident_offsets, incident_tets, i); }

 private:
  static IndexRun run(const std::vector<int>& offsets, const std::vector<int>& items, int i) {
    const int* data = items.data();
    return {data + offsets[std::size_t(i)], data + offsets[std::size_t(i) + 1]};
  }
};

/// Triangulates `points` (n x 3) weighted by `values` (n; squared as weights for Regular).
/// The output does not depend on the thread count: CGAL's symbolic perturbation makes the
/// triangulation unique, and the tetrahedra are put in a canonical order.
/// Throws Error if there are fewer than 4 samples or all samples are coplanar.
Triangulation triangulate(const PointMatrix& points, const Eigen::VectorXd& values,
                          const TriangulationOptions& options = {});

}  // namespace sdfcontour
