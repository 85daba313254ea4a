// Internal: the sampling density (points per unit area) around each point, which sets each
// normal's weight (the area it stands for) and the depth it is splatted at.
#pragma once

#include <vector>

#include "reconstruction/poisson/keys.h"
#include "reconstruction/poisson/points.h"

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
/// samples_per_node points, clamped to [min_depth, max_depth]); returns the mean area. With
/// `fractional`, the normal is shared between the two depths around that (fractional) depth;
/// else it goes whole to the nearest. Measured (docs/poisson_degree2.md): sharing brings degree 2
/// within 5% of MeshLab on all 34 cases at alpha 2 (the icosphere's surface points: 1.26x ->
/// 0.94x), but costs degree 1 at our alpha 10 (the icosphere 11%, GCP on bunny 256^3 1%), so
/// poisson_reconstruct shares for degree 2 alone.
double assign_areas_and_depths(std::vector<UnitPoint>& points, const SamplingDensity& density,
                               double samples_per_node, int min_depth, int max_depth,
                               bool fractional);

}  // namespace sdfcontour::poisson
