// Internal: the sampling density (points per unit area) around each point, which sets each
// normal's weight (the area it stands for) and the depth it is splatted at.
#pragma once

#include <vector>

#include "keys.h"
#include "points.h"

namespace sdfcontour::poisson {

/// Unit weights splatted trilinearly at depth `depth` and smoothed with [1 2 1]/4 along each
/// axis; read back per unit area.
class SamplingDensity {
 public:
  SamplingDensity(const std::vector<UnitPoint>& points, const MortonRuns& runs, int depth);
  /// Estimated points per unit area (unit-cube units) around unit-cube point p.
  double points_per_area(const Eigen::Vector3d& p) const;

 private:
  void smooth(int axis);
  long res_;
  double h_;
  std::vector<Key> nodes_;
  std::vector<double> values_;
  KeyIndex index_;
};

/// Sets each point's area (1 / density) and splat depth (where a node of side h holds about
/// samples_per_node points, clamped to [min_depth, max_depth]); returns the mean area.
double assign_areas_and_depths(std::vector<UnitPoint>& points, const SamplingDensity& density,
                               double samples_per_node, int min_depth, int max_depth);

}  // namespace sdfcontour::poisson
