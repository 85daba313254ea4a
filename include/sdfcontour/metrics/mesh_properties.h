// Basic properties of triangle meshes: closedness, orientation, area, enclosed volume.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Edge-based topology of a triangle mesh.
struct MeshTopology {
  bool closed = false;                 ///< every edge has exactly two incident triangles
  bool consistently_oriented = false;  ///< every interior edge is used once in each direction
  long boundary_edges = 0;             ///< edges with one incident triangle
  long nonmanifold_edges = 0;          ///< edges with more than two incident triangles
  long euler_characteristic = 0;       ///< V - E + F over referenced vertices
};

MeshTopology mesh_topology(const Mesh& mesh);
/// Number of connected components (triangles sharing a vertex are connected).
int connected_components(const Mesh& mesh);
/// Per vertex, its connected component (numbered by first vertex), or -1 if no triangle uses it.
std::vector<int> component_labels(const Mesh& mesh);
/// Per component of `labels` (component_labels of `mesh`), the bounding box of its vertices.
std::vector<Eigen::AlignedBox3d> component_boxes(const Mesh& mesh, const std::vector<int>& labels);
/// Removes the pieces (connected components) whose bounding box is under `min_extent` on every
/// axis, unless that would remove every piece; unused vertices go too. Returns how many pieces.
int remove_small_pieces(Mesh& mesh, double min_extent);
/// Total triangle area.
double surface_area(const Mesh& mesh);
/// Signed enclosed volume (divergence theorem): positive for a closed, outward-oriented mesh.
double signed_volume(const Mesh& mesh);

}  // namespace sdfcontour
