// A brick's stages after its contact points (brick_stages.h).
#include "reconstruction/local/brick_stages.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <utility>

#include "contact_points/lattice_spheres.h"
#include "reconstruction/carving_internal.h"
#include "reconstruction/local/brick_moves.h"
#include "reconstruction/local/brick_ownership.h"
#include "reconstruction/local/brick_reach.h"
#include "reconstruction/local/edge_fans.h"
#include "reconstruction/local/keyed_local_mesh.h"
#include "reconstruction/local/thin_parts.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/contact_projection.h"

namespace sdfcontour::detail {

namespace {

// The reconstruction's options on a grid `scale` times finer: its lengths in that grid's
// spacings, and (scale > 1) its narrow cells.
LocalReconstructionOptions on_finer_grid(LocalReconstructionOptions o, int scale) {
  o.reach *= scale, o.empty_cell_reach *= scale, o.max_field_miss *= scale;
  o.depth_scale *= scale, o.robust_scale *= scale;
  o.narrow_cells = scale > 1;
  return o;
}

// An edge-fanned mesh's vertices back into their fan regions (keep_in_fan_regions): per vertex of
// `sub`, its crossings' mean where it is a dual vertex (`keys`: the dual mesh's vertices' names).
void keep_fans_in_regions(const std::vector<std::uint64_t>& keys, const BrickDual& dual,
                          const SampleSpheres* spheres, BrickSurface& surface) {
  const PointMatrix& means = dual.crossing_means;
  SubdividedMesh& sub = surface.sub;
  PointMatrix sub_means = sub.mesh.vertices;
  std::vector<std::pair<std::uint64_t, Eigen::Index>> named(keys.size());
  for (std::size_t v = 0; v < keys.size(); ++v) named[v] = {keys[v], Eigen::Index(v)};
  tbb::parallel_sort(named.begin(), named.end());
  tbb::parallel_for(std::size_t(0), sub.keys.size(), [&](std::size_t v) {
    if (sub.keys[v][1] != 0) return;
    const auto it = std::lower_bound(named.begin(), named.end(),
                                     std::pair<std::uint64_t, Eigen::Index>{sub.keys[v][0], 0});
    if (it != named.end() && it->first == sub.keys[v][0])
      sub_means.row(Eigen::Index(v)) = means.row(it->second);
  });
  keep_in_fan_regions(sub.mesh.vertices, sub.keys, surface.reconstructed, sub_means,
                      dual.split_cells, dual.cells, spheres);
}

}  // namespace

BrickDual brick_dual_mesh(const GridView& block, const BandSamples& band, const ContactPoints& cp,
                          const Eigen::VectorXd& depths, const Index3& own_first,
                          const Index3& own_end, const LocalBrickOptions& options,
                          LocalPiece& piece) {
  const bool refine = local_thin_parts(options, block.whole_dims());
  RefinedGrid refined;
  if (refine)
    refined = refine_for_thin_parts(block, cp.points, cp.normals, options.band.value_scale,
                                    grid_truncation(band.truncation, options.band.value_scale));
  const GridView& cells_grid = refine ? refined.view : block;
  BrickDual dual;
  dual.cells = cells_grid;
  dual.scale = refine ? 2 : 1;
  const Index3 cells_n = cells_grid.whole_dims();
  dual.cells_first = times(own_first, dual.scale), dual.cells_end = times(own_end, dual.scale);
  const LocalReconstructionOptions local = on_finer_grid(options.local, dual.scale);
  // Only the cells around those edges: the four cells of an edge from point e lie in [e - 1, e];
  // the box holds one cell more on each side.
  const int ring = dual.scale * edge_ring(options);
  const Index3 edges_lo = shifted(dual.cells_first, -ring),
               edges_hi = shifted(dual.cells_end, ring);
  std::array<Index3, 2> cell_box;
  for (std::size_t a = 0; a < 3; ++a) {
    cell_box[0][a] = edges_lo[a] - 2 - cells_grid.first[a];
    cell_box[1][a] = edges_hi[a] + 1 - cells_grid.first[a];
  }
  const KeyedLocalMesh keyed = keyed_local_reconstruction(cells_grid, cp.points, cp.normals, local,
                                                          nullptr, depths, &cell_box);
  piece.stats = owned_cell_stats(keyed, cells_n, dual.cells_first, dual.cells_end);
  if (local.edge_fans) dual.split_cells = split_cells(keyed.vertex_key, cells_n);
  for (const Index3& t : refined.thin_points)
    piece.stats.thin_points += in_range(t, dual.cells_first, dual.cells_end);
  dual.near = triangles_of_edges(keyed, cells_n, edges_lo, edges_hi, dual.crossing_means);
  return dual;
}

void settle_dual_vertices(const GridView& block, const BandSamples& band,
                          const LocalBrickOptions& options, BrickDual& dual) {
  if (options.refine_zero_set) {
    Mesh mesh{std::move(dual.near.vertices), dual.near.triangles};
    refine_vertices_on_zero_set(block, band, options, mesh, nullptr, nullptr, &dual.crossing_means);
    dual.near.vertices = std::move(mesh.vertices);
  }
  if (options.untangle) {
    Mesh mesh{std::move(dual.near.vertices), dual.near.triangles};
    revert_self_intersections(mesh, dual.crossing_means, kDualUntangleRounds);
    dual.near.vertices = std::move(mesh.vertices);
  }
}

BrickSurface surface_on_contact_points(const BrickDual& dual, const ContactPoints& cp,
                                       const Eigen::VectorXd& depths, double h, const Index3& n,
                                       const LocalBrickOptions& options) {
  const bool fans = options.local.edge_fans;
  const int largest = *std::max_element(n.begin(), n.end());
  const int levels = fans ? 0
                          : std::max(0, (options.subdivisions >= 0 ? options.subdivisions
                                                                   : auto_subdivisions(largest)) -
                                            (dual.scale - 1));
  BrickSurface surface;
  SubdividedMesh& sub = surface.sub = lattice_subdivision(dual.near, levels);
  surface.reconstructed = sub.mesh.vertices;
  // Sharp edges stay as the quadrics put them: the smooth fit and the balls would round them.
  // Corners that the samples around them share (exact, as a box's) stay always.
  surface.corners = shared_corners(sub);
  // (The points indexed once, for the split's vertices too.)
  std::optional<ContactProjector> projector;
  const double sag = options.split_sag >= 0 ? options.split_sag : auto_split_sag(largest);
  // (Not where the values are no distances: the vertices then go onto the grid's zero set, not
  // onto the contact points' fit that the split follows; the quartic torus at 64^3 had new
  // vertices 0.002 h off it.)
  const bool project = options.project && cp.size() > 0;
  const bool split = project && sag > 0 && !options.refine_zero_set && (fans || levels <= 3);
  if (project) {
    projector.emplace(cp.points, cp.normals, depths, h, options.projection);
    // The split reads every vertex's triangles: made once for both.
    const VertexTriangles around(sub.mesh, split ? nullptr : &surface.fixed(options));
    ChordOffsets* chords = fans || !options.keep_chord_offsets ? nullptr : &surface.chords;
    projector->project(sub.mesh, &surface.fixed(options), around, chords);
    if (split && fans) {
      split_fan_faces(dual.near, sag * h, *projector, dual.cells, around, sub,
                      surface.reconstructed);
      surface.corners = shared_corners(sub);  // in the new numbering
    } else if (split) {
      split_sagging_edges(dual.near, levels, sag * h, *projector, options, around, sub,
                          surface.reconstructed, surface.corners, chords);
    }
  }
  surface.stay = surface.fixed(options);
  return surface;
}

void settle_vertices(const GridGeometry& block_geometry, const BandSamples& band,
                     std::optional<BandSamples> wider, const LocalBrickOptions& options,
                     const std::vector<std::uint64_t>& dual_keys, const BrickDual& dual,
                     BrickSurface& surface) {
  const double h = block_geometry.spacing().maxCoeff();
  Mesh& mesh = surface.sub.mesh;
  const bool fans = options.local.edge_fans;
  const BandSamples& balls = wider ? *wider : band;
  // The band's lattice, made once for the carving (where its balls are the band's) and the fans.
  std::optional<Lattice> band_lattice;
  if (options.carve && options.carve_passes > 0 && balls.samples.points.rows() > 0) {
    std::optional<Lattice> wider_lattice;
    const Lattice& lattice = wider ? wider_lattice.emplace(block_geometry, balls)
                                   : band_lattice.emplace(block_geometry, band);
    // (A vertex may lie inside a ball by its chord offset: the offset puts it off a smooth
    // surface on purpose, so that its flat triangles straddle it.)
    std::vector<double> allowance;
    if (surface.chords.size() == std::size_t(mesh.vertices.rows())) {
      allowance.resize(surface.chords.size());
      for (std::size_t v = 0; v < allowance.size(); ++v)
        allowance[v] = std::abs(surface.chords.offset[v]) * h;
    }
    carve_vertices_alone(mesh.vertices, lattice, &balls.core, h, options.carve_passes,
                         kMaxCarveMove, surface.stay.empty() ? nullptr : &surface.stay,
                         allowance.empty() ? nullptr : &allowance);
  }
  wider.reset();
  if (!fans) band_lattice.reset();
  if (options.refine_zero_set && options.grid_read) options.grid_read();
  if (options.side_rounds > 0) put_samples_on_their_sides(mesh, band, h, options.side_rounds);
  if (fans) {
    // On the grid itself, where the values are distances (as the carving takes them), the
    // samples' spheres bound the edges' vertices too.
    const bool distances = options.carve && dual.scale == 1 && !options.refine_zero_set &&
                           band.samples.points.rows() > 0;
    std::optional<SampleSpheres> spheres;
    if (distances) {
      if (!band_lattice) band_lattice.emplace(block_geometry, band);
      spheres.emplace(*band_lattice, block_geometry.first);
    }
    keep_fans_in_regions(dual_keys, dual, spheres ? &*spheres : nullptr, surface);
  }
  // The grid's box holds the mesh: the projection can push a vertex by its side a hair beyond
  // (a sphere cut by the side x = 0.3 at 48^3: 0.001 h), and a clamp that makes a crossing is
  // undone after.
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
    mesh.vertices.row(v) = mesh.vertices.row(v)
                               .cwiseMax(block_geometry.bounds.min.transpose())
                               .cwiseMin(block_geometry.bounds.max.transpose());
  });
}

void untangle_moves(const BandSamples& band, double h, const LocalBrickOptions& options,
                    BrickSurface& surface) {
  Mesh& mesh = surface.sub.mesh;
  std::vector<char> reverted;
  revert_self_intersections(mesh, surface.reconstructed, kUntangleRounds, &reverted);
  if (options.side_rounds > 0 &&
      std::any_of(reverted.begin(), reverted.end(), [](char r) { return r != 0; })) {
    const PointMatrix settled = mesh.vertices;
    put_samples_on_their_sides(mesh, band, h, 1, &reverted);
    revert_self_intersections(mesh, settled, 1);
  }
}

}  // namespace sdfcontour::detail
