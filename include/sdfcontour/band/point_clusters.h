// Points grouped into clusters that lie apart: the objects of a scene.
#pragma once

#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Per row of `points` (n x 3), its cluster: two points share a cluster when a chain of points
/// joins them whose cubes of side `cell` (a fixed grid of them) touch, face, edge or corner.
/// Points farther than 2 * `cell` apart with nothing between them end in different clusters.
/// Clusters are numbered 0, 1, ... in the order of their first row. Memory follows the points,
/// not their extent. Throws Error unless `cell` is positive and finite.
std::vector<int> point_clusters(const PointMatrix& points, double cell);

}  // namespace sdfcontour
