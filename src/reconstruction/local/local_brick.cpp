// One brick of the local reconstruction (local_brick.h): the block's band and contact points
// (certified stars only), the keyed dual mesh around the owned edges, lattice subdivision and
// projection, then the owned triangles.
#include "sdfcontour/reconstruction/local_brick.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "contact_points/lattice_spheres.h"
#include "reconstruction/carving_internal.h"
#include "reconstruction/free_memory.h"
#include "reconstruction/local/brick_moves.h"
#include "reconstruction/local/brick_ownership.h"
#include "reconstruction/local/edge_fans.h"
#include "reconstruction/local/keyed_local_mesh.h"
#include "reconstruction/local/lattice_subdivision.h"
#include "reconstruction/local/thin_parts.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour {

namespace {

using detail::in_range;
using detail::Index3;

// Adds the seconds since the last call to a step's entry.
class StepClock {
 public:
  explicit StepClock(std::array<double, 6>& seconds) : seconds_(seconds) {}
  void next(std::size_t step) {
    const auto now = std::chrono::steady_clock::now();
    seconds_[step] += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }

 private:
  std::array<double, 6>& seconds_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// The band's options with its auto band (0) resolved for the whole grid of `dims` (and the
// contact points that the bricks make there).
BandOptions resolved_band(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  BandOptions band = options.band;
  if (band.band == 0)
    band.band = auto_local_band(*std::max_element(dims.begin(), dims.end()),
                                local_lattice_points(options, dims));
  return band;
}

// The largest |value| a band sample can have, in spacings. With every sample (band 'all') no
// sphere reaches farther than the grid's diagonal matters.
double largest_in_spacings(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  const double largest = resolved_band(options, dims).band + options.band.margin;
  if (std::isfinite(largest)) return largest;
  return std::sqrt(3.0) * *std::max_element(dims.begin(), dims.end());
}

// Grid edges beyond the owned ones whose triangles a brick computes: their vertices' normals
// need one ring; undoing crossings needs kUntangleRing (the dual mesh's rounds alone, fewer).
int ring(const LocalBrickOptions& o) {
  const int split = o.split_sag != 0 ? kSplitReach : 0;
  if (!o.untangle) return 1 + split;
  return (o.project || o.carve ? kUntangleRing : 1 + kCrossingReach * kDualUntangleRounds) + split;
}

// How far beyond the owned samples a contact point can matter, in samples: the reach of the
// ring of cells around the owned edges' cells (2), of a vertex's gathering or projection, and
// of a sample to its contact point (its |value|).
int flag_reach(const LocalBrickOptions& o, double largest, const std::array<int, 3>& dims) {
  const double gather =
      std::max({o.local.reach, o.local.empty_cell_reach,
                o.project ? std::max(o.projection.radius, o.projection.wide_radius) : 0.0});
  return int(std::ceil(gather + largest)) + 2 + ring(o) +
         (local_thin_parts(o, dims) ? kThinPartReach : 0);
}

Index3 shifted(const Index3& p, int by) {
  return {p[0] + by, p[1] + by, p[2] + by};
}

Index3 times(const Index3& p, int factor) {
  return {p[0] * factor, p[1] * factor, p[2] * factor};
}

// The reconstruction's options on a grid `scale` times finer: its lengths in that grid's
// spacings, and (scale > 1) its narrow cells.
LocalReconstructionOptions on_finer_grid(LocalReconstructionOptions o, int scale) {
  o.reach *= scale, o.empty_cell_reach *= scale, o.max_field_miss *= scale;
  o.depth_scale *= scale, o.robust_scale *= scale;
  o.narrow_cells = scale > 1;
  return o;
}

// True if the block's samples in the global range [lo, hi) (clipped to the block) have both
// signs, or with `near` > 0 one closer to the surface than that (a thin part may pass there).
bool has_surface(const GridView& block, const Index3& lo, const Index3& hi, double near) {
  Index3 a, b;
  for (std::size_t d = 0; d < 3; ++d) {
    a[d] = std::max(lo[d] - block.first[d], 0);
    b[d] = std::min(hi[d] - block.first[d], block.dims[d]);
    if (a[d] >= b[d]) return false;
  }
  bool inside = false, outside = false;
  for (int i = a[0]; i < b[0]; ++i)
    for (int j = a[1]; j < b[1]; ++j)
      for (int k = a[2]; k < b[2]; ++k) {
        const double v = block.value(block.index(i, j, k));
        (v < 0 ? inside : outside) = true;
        if ((inside && outside) || std::abs(v) < near) return true;
      }
  return false;
}

// The box in which the block's samples are all the whole grid's: unbounded where the block
// reaches the grid's side.
Bounds certain_box(const GridView& block) {
  const Index3 n = block.whole_dims();
  const Eigen::Vector3d lo = block.point(0, 0, 0),
                        hi = block.point(block.dims[0] - 1, block.dims[1] - 1, block.dims[2] - 1);
  Bounds b;
  for (std::size_t a = 0; a < 3; ++a) {
    b.min[Eigen::Index(a)] =
        block.first[a] == 0 ? -std::numeric_limits<double>::infinity() : lo[Eigen::Index(a)];
    b.max[Eigen::Index(a)] = block.first[a] + block.dims[a] == n[a]
                                 ? std::numeric_limits<double>::infinity()
                                 : hi[Eigen::Index(a)];
  }
  return b;
}

void validate(const GridView& block, const Index3& own_first, const Index3& own_end,
              const LocalBrickOptions& o) {
  validate_grid_geometry(block);
  // Named by its global [i, j, k], in the words of the marching cubes bricks.
  const auto at = block.values_checked ? std::nullopt : first_non_finite(block);
  if (at)
    throw Error("the grid has a non-finite value at [" + std::to_string((*at)[0]) + ", " +
                std::to_string((*at)[1]) + ", " + std::to_string((*at)[2]) + "]");
  const Index3 n = block.whole_dims();
  for (std::size_t a = 0; a < 3; ++a) {
    if (block.dims[a] < 2 || block.first[a] < 0 || block.first[a] + block.dims[a] > n[a])
      throw Error("a brick's block must hold at least 2 samples per axis inside its grid");
    if (!(own_first[a] >= 0 && own_first[a] < own_end[a] && own_end[a] <= n[a]))
      throw Error("a brick's owned samples must be a non-empty range inside its grid");
  }
  if (o.band.truncation_mode == TruncationMode::Auto)
    throw Error("a brick needs its grid's truncation resolved on the whole grid");
  require_nameable(n, o);
  if (o.subdivisions < -1 || o.subdivisions > 4)
    throw Error("the local reconstruction's subdivisions must lie in 0..4 (-1: auto)");
}

// The block's band; none where it has no usable one (its cells then use their edge crossings).
BandSamples brick_band(const GridView& block, const LocalBrickOptions& options) {
  try {
    return select_band(block, resolved_band(options, block.whole_dims()));
  } catch (const InternalError&) {
    throw;
  } catch (const Cancelled&) {
    throw;
  } catch (const Error&) {
    BandSamples band;
    band.band = options.band.band;
    return band;
  }
}

// Throws HaloTooSmall unless every flagged sample lies lattice_contact_reach samples inside the
// block's sides that are not the whole grid's: its point then reads what the whole grid's would.
// (The reach is the whole grid's: any band sample's |value| is at most `largest`, a block's own
// largest may be smaller than a sphere just outside it.)
void require_lattice_reach(const GridView& block, const BandSamples& band,
                           const std::vector<char>& flagged, const ContactPointOptions& contact,
                           double largest) {
  const int reach = lattice_contact_reach(block, largest, contact);
  const Index3 n = block.whole_dims();
  Index3 lo, hi;  // the block's indices that the flagged samples may take
  for (std::size_t a = 0; a < 3; ++a) {
    lo[a] = block.first[a] == 0 ? 0 : reach;
    hi[a] = block.first[a] + block.dims[a] == n[a] ? block.dims[a] - 1 : block.dims[a] - 1 - reach;
  }
  for (std::size_t s = 0; s < flagged.size(); ++s) {
    if (!flagged[s]) continue;
    const long p = band.source[s];
    const Index3 at{int(p / (long(block.dims[1]) * block.dims[2])),
                    int(p / block.dims[2] % block.dims[1]), int(p % block.dims[2])};
    for (std::size_t a = 0; a < 3; ++a)
      if (at[a] < lo[a] || at[a] > hi[a])
        throw HaloTooSmall("a lattice contact point reads beyond its brick's block");
  }
}

// The given contact points of the samples in [lo, hi] (global, inclusive), in their order.
ContactPoints given_in_reach(const GivenContactPoints& given, const Index3& n, const Index3& lo,
                             const Index3& hi, Eigen::VectorXd& depths) {
  std::vector<Eigen::Index> rows;
  for (std::size_t q = 0; q < given.samples.size(); ++q) {
    const Index3 at = detail::grid_point_of(given.samples[q], n);
    bool in = true;
    for (std::size_t a = 0; a < 3; ++a) in = in && at[a] >= lo[a] && at[a] <= hi[a];
    if (in) rows.push_back(Eigen::Index(q));
  }
  ContactPoints cp;
  cp.points = given.points(rows, Eigen::all);
  cp.normals = given.normals(rows, Eigen::all);
  depths = given.depths(rows);
  cp.samples.resize(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) cp.samples[r] = int(r);
  return cp;
}

// The contact points of the band samples that the owned part [own_first, own_end) can use (within
// flag_reach of it), from the block's triangulation with certified stars, its lattice, or the
// given points; `depths`: their samples' |value|.
ContactPoints owned_reach_contact_points(const GridView& block, const BandSamples& band,
                                         const Index3& own_first, const Index3& own_end,
                                         const LocalBrickOptions& options,
                                         Eigen::VectorXd& depths) {
  const double h = block.spacing().maxCoeff();
  const Index3 n = block.whole_dims();
  const double largest = largest_in_spacings(options, n) * h;
  const int reach = flag_reach(options, largest / h, n);
  if (options.given_points)
    return given_in_reach(*options.given_points, n, shifted(own_first, -reach),
                          shifted(own_end, reach), depths);
  auto with_depths = [&](ContactPoints cp) {
    depths = contact_depths(cp, band.samples.values);
    return cp;
  };
  const Eigen::Vector3d flag_lo =
      block.point(own_first[0] - reach - block.first[0], own_first[1] - reach - block.first[1],
                  own_first[2] - reach - block.first[2]);
  const Eigen::Vector3d flag_hi =
      block.point(own_end[0] + reach - block.first[0], own_end[1] + reach - block.first[1],
                  own_end[2] + reach - block.first[2]);
  const Eigen::Index count = band.samples.points.rows();
  std::vector<char> flagged(std::size_t(count), 0);
  tbb::parallel_for(Eigen::Index(0), count, [&](Eigen::Index i) {
    const Eigen::Vector3d p = band.samples.points.row(i).transpose();
    flagged[std::size_t(i)] = band.core[std::size_t(i)] && (p.array() >= flag_lo.array()).all() &&
                              (p.array() <= flag_hi.array()).all();
  });
  if (local_lattice_points(options, n)) {
    require_lattice_reach(block, band, flagged, options.lattice_contact, largest);
    ContactPointOptions contact = options.lattice_contact;
    contact.exact_wedge_slopes = contact.exact_wedge_slopes && block.type == ScalarType::Float64;
    return with_depths(lattice_contact_points(block, band, contact, &flagged));
  }
  const Bounds within = certain_box(block);
  BrickOptions bricks;
  bricks.halo = auto_brick_halo(largest, h);
  bricks.within = &within;
  bricks.largest_value = largest;
  bricks.weight_cap_inside = band.core_inside;
  bricks.weight_cap_outside = band.core_outside;
  bricks.cancel = options.cancel;
  ContactPoints cp;
  cp.points.resize(0, 3);
  cp.normals.resize(0, 3);
  if (count > 0)
    cp = brick_contact_points(band.samples, h, options.gradient, options.contact, bricks, nullptr,
                              {}, &flagged);
  return with_depths(std::move(cp));
}

}  // namespace

void require_nameable(const Index3& dims, const LocalBrickOptions& options) {
  const double samples =
      double(dims[0]) * dims[1] * dims[2] * (local_thin_parts(options, dims) ? 8 : 1);
  constexpr double kMostSamples = 18446744073709551616.0 / 6144;
  if (samples > kMostSamples)
    throw Error("the grid's box is too large for the local reconstruction (" +
                std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                std::to_string(dims[2]) +
                " samples; at most 3e15): use --reconstruction poisson "
                "or --method mc");
}

bool local_lattice_points(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  if (options.lattice_points >= 0) return options.lattice_points > 0;
  // Values that are no distances keep the triangulation's points: on a torus's quartic implicit
  // at 64^3 the lattice's left 112 vertices that the zero set's refinement could not bring back
  // (the worst 6.9e-4 off, 2.2e-5 with the triangulation's; marching cubes 8.8e-4).
  return !options.refine_zero_set &&
         auto_lattice_points(*std::max_element(dims.begin(), dims.end()));
}

bool local_thin_parts(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  if (options.refine_zero_set) return false;
  return options.thin_parts < 0 ? auto_thin_parts(*std::max_element(dims.begin(), dims.end()))
                                : options.thin_parts > 0;
}

int local_brick_halo(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  const double largest = largest_in_spacings(options, dims);
  const int reach = flag_reach(options, largest, dims);
  // The lattice's points read lattice_contact_reach beyond the samples flagged for them, which
  // reach `reach` beyond the owned end (exclusive) inclusively; the triangulation's, the stars
  // of those samples.
  const int points =
      local_lattice_points(options, dims)
          ? reach + lattice_contact_reach(largest, options.lattice_contact) + 1
          : reach + int(auto_brick_halo(largest, 1.0)) + int(std::ceil(2 * largest)) + 1;
  // Carving: the balls around the owned edges' vertices (within 2 cells of the owned samples).
  return std::max(points, int(std::ceil(detail::carving_band(options, dims))) + 2 + ring(options));
}

double local_values_reach(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  return std::max(largest_in_spacings(options, dims), detail::carving_band(options, dims));
}

LocalPiece local_brick_piece(const GridView& block, const std::array<int, 3>& own_first,
                             const std::array<int, 3>& own_end, const LocalBrickOptions& options) {
  validate(block, own_first, own_end, options);
  LocalPiece piece;
  piece.vertices.resize(0, 3);
  piece.triangles.resize(0, 3);
  // The owned edges' polygons join the cells around them: no sign change there, no surface.
  const double h = block.spacing().maxCoeff();
  const Index3 n = block.whole_dims();
  const bool refine = local_thin_parts(options, n);
  // (With thin parts, a sample within a spacing of the surface, as refine_for_thin_parts reads
  // it: the values times value_scale are distances.)
  if (!has_surface(block, shifted(own_first, -1), shifted(own_end, 1),
                   refine ? h / options.band.value_scale : 0))
    return piece;
  StepClock clock(piece.seconds);
  const BandSamples band = brick_band(block, options);
  clock.next(0);
  Eigen::VectorXd depths;
  ContactPoints cp = owned_reach_contact_points(block, band, own_first, own_end, options, depths);
  piece.contact_points = cp.size();
  // The triangulation's bricks, freed in every thread's arena (the lattice's points allocate
  // little: trimming between a brick's stages only makes its next stages fault fresh pages in).
  if (!local_lattice_points(options, n)) detail::return_free_memory();
  // (Given points stay with their caller.)
  if (options.keep_contact_points && !options.given_points)
    detail::keep_owned_contact_points(block, band, cp, own_first, own_end, piece);
  clock.next(1);
  // With thin parts, the dual mesh lives on the grid at twice the resolution (thin_parts.h): its
  // cells, edges and names, with the options' reaches in its spacings and one subdivision level
  // fewer; the rest (carving, sides) reads the block's own samples.
  detail::RefinedGrid refined;
  if (refine)
    refined =
        detail::refine_for_thin_parts(block, cp.points, cp.normals, options.band.value_scale,
                                      grid_truncation(band.truncation, options.band.value_scale));
  const GridView& cells_grid = refine ? refined.view : block;
  // (Its values go once the dual mesh is made; the fans keep to its cells after that.)
  const GridGeometry cells_geometry = cells_grid;
  const int scale = refine ? 2 : 1;
  const Index3 cells_n = cells_grid.whole_dims();
  const Index3 cells_first = times(own_first, scale), cells_end = times(own_end, scale);
  const LocalReconstructionOptions local = on_finer_grid(options.local, scale);
  // The owned edges and the ring around them (their vertices' normals need every triangle); the
  // block's whole dual mesh goes once they are taken.
  PointMatrix crossing_means;
  detail::KeyedTriangles near;
  std::vector<std::uint64_t> split_cells;  // with edge fans: cells with more than one polygon
  {
    // Only the cells around those edges: the four cells of an edge from point e lie in
    // [e - 1, e]; the box holds one cell more on each side.
    const Index3 edges_lo = shifted(cells_first, -scale * ring(options)),
                 edges_hi = shifted(cells_end, scale * ring(options));
    std::array<Index3, 2> cell_box;
    for (std::size_t a = 0; a < 3; ++a) {
      cell_box[0][a] = edges_lo[a] - 2 - cells_grid.first[a];
      cell_box[1][a] = edges_hi[a] + 1 - cells_grid.first[a];
    }
    const detail::KeyedLocalMesh keyed = detail::keyed_local_reconstruction(
        cells_grid, cp.points, cp.normals, local, nullptr, depths, &cell_box);
    piece.stats = detail::owned_cell_stats(keyed, cells_n, cells_first, cells_end);
    if (local.edge_fans) split_cells = detail::split_cells(keyed.vertex_key, cells_n);
    for (const Index3& t : refined.thin_points)
      piece.stats.thin_points += in_range(t, cells_first, cells_end);
    near = detail::triangles_of_edges(keyed, cells_n, edges_lo, edges_hi, crossing_means);
  }
  refined = detail::RefinedGrid();
  // The carving's samples are taken now: where no vertex goes onto the grid's zero set, the rest
  // reads the band alone, and the block's values may go (a copied block of 567³ floats is 0.73 GB,
  // the largest part of a brick's memory through its subdivision and carving).
  const bool carve = options.carve && options.carve_passes > 0;
  // (The balls are the band's core samples, or a wider band's, which is taken from the block.)
  std::optional<BandSamples> wider =
      carve ? detail::wider_carving_band(block, options) : std::optional<BandSamples>();
  const GridGeometry block_geometry = block;
  if (!options.refine_zero_set && options.grid_read) options.grid_read();
  if (options.refine_zero_set) {
    // First the cells' own vertices: the subdivision's then start near the zero set, and so do
    // the positions that the untangling goes back to.
    Mesh dual{std::move(near.vertices), near.triangles};
    detail::refine_vertices_on_zero_set(block, band, options, dual, nullptr, nullptr,
                                        &crossing_means);
    near.vertices = std::move(dual.vertices);
  }
  if (options.untangle) {
    // The quadrics can place two nearby cells' vertices (at features) so that their triangles
    // cross: those vertices go to their crossings' mean, as an untangling of the dual mesh.
    Mesh dual{std::move(near.vertices), near.triangles};
    revert_self_intersections(dual, crossing_means, kDualUntangleRounds);
    near.vertices = std::move(dual.vertices);
  }
  clock.next(2);
  const bool fans = local.edge_fans;
  // An edge-fanned mesh keeps its dual vertices' crossing means for its split cells.
  const std::vector<std::uint64_t> fan_keys = fans ? near.vertex_key : std::vector<std::uint64_t>();
  const PointMatrix fan_means = fans ? crossing_means : PointMatrix();
  const int levels =
      fans ? 0
           : std::max(0, (options.subdivisions >= 0
                              ? options.subdivisions
                              : auto_subdivisions(*std::max_element(n.begin(), n.end()))) -
                             (scale - 1));
  detail::SubdividedMesh sub = detail::lattice_subdivision(near, levels);
  PointMatrix reconstructed = sub.mesh.vertices;
  // Sharp edges stay as the quadrics put them: the smooth fit and the balls would round them.
  // Corners that the samples around them share (exact, as a box's) stay always.
  std::vector<char> corners = detail::shared_corners(sub);
  const std::vector<char>* fixed = options.keep_features ? &sub.on_feature : &corners;
  // (The points indexed once, for the split's vertices too.)
  std::optional<ContactProjector> projector;
  if (options.project && cp.size() > 0) {
    projector.emplace(cp.points, cp.normals, depths, h, options.projection);
    projector->project(sub.mesh, fixed);
  }
  const double sag = options.split_sag >= 0 ? options.split_sag
                                            : auto_split_sag(*std::max_element(n.begin(), n.end()));
  // (Not where the values are no distances: the vertices then go onto the grid's zero set, not
  // onto the contact points' fit that the split follows; the quartic torus at 64^3 had new
  // vertices 0.002 h off it.)
  if (fans && sag > 0 && projector && !options.refine_zero_set) {
    detail::split_fan_faces(near, sag * h, *projector, cells_geometry, sub, reconstructed);
    corners = detail::shared_corners(sub);  // in the new numbering
  }
  if (!fans && sag > 0 && levels <= 3 && projector && !options.refine_zero_set)
    split_sagging_edges(near, levels, sag * h, *projector, options, sub, reconstructed, corners);
  projector.reset();
  near = detail::KeyedTriangles();
  cp = ContactPoints();
  depths = Eigen::VectorXd();
  // Where the values are no distances, their spheres are not empty either: those vertices go
  // onto the grid's own zero set and are not carved.
  std::vector<char> stay = fixed ? *fixed : std::vector<char>();
  if (options.refine_zero_set)
    detail::refine_vertices_on_zero_set(block, band, options, sub.mesh, fixed, &stay);
  clock.next(3);
  const BandSamples& balls = wider ? *wider : band;
  // The band's lattice, made once for the carving (where its balls are the band's) and the fans.
  std::optional<detail::Lattice> band_lattice;
  if (carve && balls.samples.points.rows() > 0) {
    std::optional<detail::Lattice> wider_lattice;
    const detail::Lattice& lattice = wider ? wider_lattice.emplace(block_geometry, balls)
                                           : band_lattice.emplace(block_geometry, band);
    detail::carve_vertices_alone(sub.mesh.vertices, lattice, &balls.core, h, options.carve_passes,
                                 kMaxCarveMove, stay.empty() ? nullptr : &stay);
  }
  wider.reset();
  if (!fans) band_lattice.reset();
  if (options.refine_zero_set && options.grid_read) options.grid_read();
  if (options.side_rounds > 0)
    detail::put_samples_on_their_sides(sub.mesh, band, h, options.side_rounds);
  if (fans) {
    // Per vertex of sub: its crossings' mean where it has one (the dual mesh's vertices).
    PointMatrix means = sub.mesh.vertices;
    std::vector<std::pair<std::uint64_t, Eigen::Index>> dual(fan_keys.size());
    for (std::size_t v = 0; v < fan_keys.size(); ++v) dual[v] = {fan_keys[v], Eigen::Index(v)};
    tbb::parallel_sort(dual.begin(), dual.end());
    tbb::parallel_for(std::size_t(0), sub.keys.size(), [&](std::size_t v) {
      if (sub.keys[v][1] != 0) return;
      const auto it = std::lower_bound(dual.begin(), dual.end(),
                                       std::pair<std::uint64_t, Eigen::Index>{sub.keys[v][0], 0});
      if (it != dual.end() && it->first == sub.keys[v][0])
        means.row(Eigen::Index(v)) = fan_means.row(it->second);
    });
    // On the grid itself, where the values are distances (as the carving takes them), the
    // samples' spheres bound the edges' vertices too.
    const bool distances =
        options.carve && scale == 1 && !options.refine_zero_set && band.samples.points.rows() > 0;
    std::optional<detail::SampleSpheres> spheres;
    if (distances) {
      if (!band_lattice) band_lattice.emplace(block_geometry, band);
      spheres.emplace(*band_lattice, block_geometry.first);
    }
    detail::keep_in_fan_regions(sub.mesh.vertices, sub.keys, reconstructed, means, split_cells,
                                cells_geometry, spheres ? &*spheres : nullptr);
  }
  // The grid's box holds the mesh: the projection can push a vertex by its side a hair beyond
  // (a sphere cut by the side x = 0.3 at 48^3: 0.001 h), and a clamp that makes a crossing is
  // undone below.
  tbb::parallel_for(Eigen::Index(0), sub.mesh.vertices.rows(), [&](Eigen::Index v) {
    sub.mesh.vertices.row(v) = sub.mesh.vertices.row(v)
                                   .cwiseMax(block.bounds.min.transpose())
                                   .cwiseMin(block.bounds.max.transpose());
  });
  clock.next(4);
  if (options.untangle) {
    std::vector<char> reverted;
    revert_self_intersections(sub.mesh, reconstructed, kUntangleRounds, &reverted);
    if (options.side_rounds > 0 &&
        std::any_of(reverted.begin(), reverted.end(), [](char r) { return r != 0; })) {
      // The samples near the vertices moved back, whose sides the undoing may have lost: once
      // more, without a crossing.
      const PointMatrix settled = sub.mesh.vertices;
      detail::put_samples_on_their_sides(sub.mesh, band, h, 1, &reverted);
      revert_self_intersections(sub.mesh, settled, 1);
    }
  }
  clock.next(5);
  detail::take_owned_part(sub, cells_n, cells_first, cells_end, piece);
  return piece;
}

}  // namespace sdfcontour
