// One brick of the local reconstruction (local_brick.h): the block's band and contact points
// (certified stars only), then brick_stages.h's stages, then the owned triangles.
#include "sdfcontour/reconstruction/local_brick.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "reconstruction/free_memory.h"
#include "reconstruction/local/brick_moves.h"
#include "reconstruction/local/brick_ownership.h"
#include "reconstruction/local/brick_reach.h"
#include "reconstruction/local/brick_stages.h"
#include "reconstruction/local/lattice_point_store.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
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
    return select_band(block, detail::resolved_band(options, block.whole_dims()));
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
    const Index3 at = detail::grid_point_of(std::uint64_t(band.source[s]), block.dims);
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
  const double largest = detail::largest_in_spacings(options, n) * h;
  const int reach = detail::flag_reach(options, largest / h, n);
  if (options.given_points)
    return given_in_reach(*options.given_points, n, detail::shifted(own_first, -reach),
                          detail::shifted(own_end, reach), depths);
  auto with_depths = [&](ContactPoints cp) {
    depths = contact_depths(cp, band.samples.values);
    return cp;
  };
  // The global samples [flag_lo, flag_hi] (inclusive).
  const Index3 flag_lo = detail::shifted(own_first, -reach),
               flag_hi = detail::shifted(own_end, reach);
  const Eigen::Index count = band.samples.points.rows();
  std::vector<char> flagged(std::size_t(count), 0);
  tbb::parallel_for(Eigen::Index(0), count, [&](Eigen::Index i) {
    const Index3 at = detail::global_sample(block, band, std::size_t(i));
    bool in = band.core[std::size_t(i)];
    for (std::size_t a = 0; a < 3; ++a) in = in && at[a] >= flag_lo[a] && at[a] <= flag_hi[a];
    flagged[std::size_t(i)] = in;
  });
  if (local_lattice_points(options, n)) {
    require_lattice_reach(block, band, flagged, options.lattice_contact, largest);
    ContactPointOptions contact = options.lattice_contact;
    contact.exact_wedge_slopes = contact.exact_wedge_slopes && block.type == ScalarType::Float64;
    if (!options.lattice_store)
      return with_depths(lattice_contact_points(block, band, contact, &flagged));
    const ContactPoints stored =
        options.lattice_store->take(block, band, flag_lo, flag_hi, flagged);
    const ContactPoints made = lattice_contact_points(block, band, contact, &flagged);
    // (A later brick's reach begins reach samples before this one's owned end, along some axis.)
    options.lattice_store->record(block, band, flag_lo, flag_hi,
                                  detail::shifted(own_end, -reach - 1), made);
    return with_depths(detail::merged_contact_points(made, stored));
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

LocalPiece local_brick_piece(const GridView& block, const std::array<int, 3>& own_first,
                             const std::array<int, 3>& own_end, const LocalBrickOptions& options) {
  validate(block, own_first, own_end, options);
  LocalPiece piece;
  piece.vertices.resize(0, 3);
  piece.triangles.resize(0, 3);
  // The owned edges' polygons join the cells around them: no sign change there, no surface.
  const double h = block.spacing().maxCoeff();
  const Index3 n = block.whole_dims();
  // (With thin parts, a sample within a spacing of the surface, as refine_for_thin_parts reads
  // it: the values times value_scale are distances.)
  if (!has_surface(block, detail::shifted(own_first, -1), detail::shifted(own_end, 1),
                   local_thin_parts(options, n) ? h / options.band.value_scale : 0))
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
  detail::BrickDual dual =
      detail::brick_dual_mesh(block, band, cp, depths, own_first, own_end, options, piece);
  // The carving's samples are taken now: where no vertex goes onto the grid's zero set, the rest
  // reads the band alone, and the block's values may go (a copied block of 567³ floats is 0.73 GB,
  // the largest part of a brick's memory through its subdivision and carving).
  std::optional<BandSamples> wider = options.carve && options.carve_passes > 0
                                         ? detail::wider_carving_band(block, options)
                                         : std::optional<BandSamples>();
  const GridGeometry block_geometry = block;
  if (!options.refine_zero_set && options.grid_read) options.grid_read();
  detail::settle_dual_vertices(block, band, options, dual);
  clock.next(2);
  detail::BrickSurface surface = detail::surface_on_contact_points(dual, cp, depths, h, n, options);
  // (An edge-fanned mesh keeps its dual vertices' names, with their crossing means.)
  const std::vector<std::uint64_t> dual_keys =
      options.local.edge_fans ? std::move(dual.near.vertex_key) : std::vector<std::uint64_t>();
  dual.near = detail::KeyedTriangles();
  cp = ContactPoints();
  depths = Eigen::VectorXd();
  // Where the values are no distances, their spheres are not empty either: those vertices go
  // onto the grid's own zero set and are not carved.
  if (options.refine_zero_set)
    detail::refine_vertices_on_zero_set(block, band, options, surface.sub.mesh,
                                        &surface.fixed(options), &surface.stay);
  clock.next(3);
  detail::settle_vertices(block_geometry, band, std::move(wider), options, dual_keys, dual,
                          surface);
  clock.next(4);
  if (options.untangle) detail::untangle_moves(band, h, options, surface);
  clock.next(5);
  detail::take_owned_part(surface.sub, dual.cells.whole_dims(), dual.cells_first, dual.cells_end,
                          piece);
  return piece;
}

}  // namespace sdfcontour
