// Placing meshes in the unit-ish box the experiments use, and cutting them to a box.
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Scales `mesh` uniformly about its bounding box's centre, moved to the origin, so that its
/// longest side spans [-half_extent, half_extent]. Throws Error for an empty or flat-as-a-point
/// mesh.
Mesh normalize_mesh(const Mesh& mesh, double half_extent);

/// Appends `part`'s vertices and triangles to `mesh` (its triangles renumbered after `mesh`'s
/// vertices).
void append_mesh(Mesh& mesh, const Mesh& part);

/// Cuts `mesh` to the box [min, max]: triangles outside are dropped, triangles across a side are
/// cut along it (new vertices exactly on the side, shared by the triangles on both sides of an
/// edge, so the cut mesh stays connected), unused vertices removed. Vertices on a side count as
/// inside. Returns whether any triangle was dropped or cut; a mesh inside the box is left as it
/// was.
bool clip_mesh_to_box(Mesh& mesh, const Eigen::Vector3d& min, const Eigen::Vector3d& max);

}  // namespace sdfcontour
