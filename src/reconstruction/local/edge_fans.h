// Internal: the vertices of an edge-fanned local mesh (LocalReconstructionOptions::edge_fans)
// kept where they cannot make it cross itself.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "contact_points/lattice_spheres.h"
#include "reconstruction/local/lattice_subdivision.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

/// Where keyed_local_reconstruction's vertex keys start, on a grid of `n` points (whole grid):
/// cell vertices are 4 * cell + polygon, below `segments`; segment vertices `segments` + (3 *
/// face point + axis) * 4 + corner, below `edges`; edge vertices `edges` + 3 * point + axis.
struct VertexKeyBases {
  std::uint64_t segments = 0, edges = 0;
};
VertexKeyBases vertex_key_bases(const std::array<int, 3>& n);

/// The band samples' spheres by grid point (radius |value|: where the values are distances, a
/// sphere holds no surface), on the block `lattice` was made on.
class SampleSpheres {
 public:
  SampleSpheres(const Lattice& lattice, const std::array<int, 3>& block_first)
      : lattice_(lattice), first_(block_first) {}
  /// The radius of the sphere of the sample at whole-grid point p; 0 where p is not in the band.
  double radius(const std::array<int, 3>& p) const;

 private:
  const Lattice& lattice_;
  std::array<int, 3> first_;
};

/// After the vertices of an edge-fanned mesh moved from `before` (the projection onto the contact
/// points), each goes back into its region: a cell's vertex into its cell (a thousandth of the
/// cell inside; slid along the sides that hold it back to the plane through its new place,
/// normal to its move), an edge's vertex onto its grid edge and a face's vertex (split_fan_faces)
/// onto its face, where the plane through its new place, normal to its move, meets them (a
/// thousandth of a spacing inside), a segment's vertex back where it was (on its face). `keys`: the
/// vertices' names (lattice_subdivision's at level 0, split_curved_edges' for face vertices);
/// `grid`: the grid (or block) the keys were made on. A cell with more than one polygon
/// (`split_cells`: ascending cell numbers, split_cells() of the whole dual mesh) holds as many
/// cones, which its vertices alone cannot keep apart: they go to `crossing_means` (per vertex:
/// the mean of its polygon's edge crossings, as marching cubes' polygons lie). With `spheres`
/// (on the same grid), an edge's vertex also stays out of its two samples' spheres, where they
/// leave room. Returns the vertices that had to be put back.
long keep_in_fan_regions(PointMatrix& vertices, const std::vector<VertexKey>& keys,
                         const PointMatrix& before, const PointMatrix& crossing_means,
                         const std::vector<std::uint64_t>& split_cells, const GridGeometry& grid,
                         const SampleSpheres* spheres = nullptr);

/// The cells (4 * cell + polygon keys / 4) that hold more than one polygon, ascending, among the
/// dual mesh's vertex keys `keys` on a grid of `n` points.
std::vector<std::uint64_t> split_cells(const std::vector<std::uint64_t>& keys,
                                       const std::array<int, 3>& n);

/// Refinement where it pays, inside the regions: each edge of `sub` (an edge-fanned mesh at
/// level 0, projected) between two cells' vertices, whose chord sags by more than `limit` (its
/// length times its ends' normals' turn / 8) gets a vertex where it crosses the face between the
/// two cells, projected by `projector` (onto the contact points) and kept on that face; each of its
/// two triangles is cut in two, each half in one cell. `reconstructed` follows the new numbering
/// (the new vertices at their faces' crossings). `around`: sub.mesh's triangles around each vertex.
void split_fan_faces(const KeyedTriangles& near, double limit, const ContactProjector& projector,
                     const GridGeometry& grid, const VertexTriangles& around, SubdividedMesh& sub,
                     PointMatrix& reconstructed);

}  // namespace sdfcontour::detail
