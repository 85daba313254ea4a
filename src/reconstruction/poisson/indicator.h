// Internal: the solved indicator function chi, evaluated anywhere in the unit cube.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "reconstruction/poisson/octree.h"

namespace sdfcontour::poisson {

/// The trilinear interpolant of node values x (one per node of L) at unit-cube point p in L's
/// active cell `cell`.
double interpolate(const OctreeLevel& L, const std::vector<double>& x,
                   const std::array<long, 3>& cell, const Eigen::Vector3d& p);

/// chi on the octree: values[d] holds chi at depth d's nodes. A point takes its value from the
/// finest depth whose active cell holds it (trilinear there).
class Indicator {
 public:
  Indicator(const Octree& tree, std::vector<std::vector<double>> values)
      : tree_(tree), values_(std::move(values)) {}

  /// Where p takes chi from: the finest depth whose active cell holds it, and that cell.
  struct Location {
    int depth = -1;  ///< -1: no active cell holds p
    std::array<long, 3> cell{};
  };
  Location locate(const Eigen::Vector3d& p) const;

  /// chi at unit-cube point p (0, "outside", if no active cell holds it).
  double at(const Eigen::Vector3d& p) const;

  /// The canonical chi at finest-depth node (i, j, k): stored where a depth has that node, else
  /// interpolated in the finest active cell holding it; `outside` beyond the domain. Cells sharing
  /// a node see one value, so meshes extracted from these values are watertight.
  double at_finest_node(long i, long j, long k, double outside) const;

  const Octree& tree() const { return tree_; }
  const std::vector<double>& values(int depth) const { return values_[std::size_t(depth)]; }
  std::vector<double>& values(int depth) { return values_[std::size_t(depth)]; }

 private:
  const Octree& tree_;
  std::vector<std::vector<double>> values_;
};

}  // namespace sdfcontour::poisson
