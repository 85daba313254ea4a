// Placing meshes in the unit-ish box the experiments use.
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Scales `mesh` uniformly about its bounding box's centre, moved to the origin, so that its
/// longest side spans [-half_extent, half_extent]. Throws Error for an empty or flat-as-a-point
/// mesh.
Mesh normalize_mesh(const Mesh& mesh, double half_extent);

}  // namespace sdfcontour
