// How far a brick of the local reconstruction reads (brick_reach.h, and local_brick.h's halo,
// values' reach and switches), from its options and the whole grid's size.
#include "reconstruction/local/brick_reach.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "reconstruction/local/brick_moves.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour {

namespace detail {

BandOptions resolved_band(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  BandOptions band = options.band;
  if (band.band == 0)
    band.band = auto_local_band(*std::max_element(dims.begin(), dims.end()),
                                local_lattice_points(options, dims));
  return band;
}

double largest_in_spacings(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  const double largest = resolved_band(options, dims).band + options.band.margin;
  if (std::isfinite(largest)) return largest;
  return std::sqrt(3.0) * *std::max_element(dims.begin(), dims.end());
}

int edge_ring(const LocalBrickOptions& o) {
  const int split = o.split_sag != 0 ? kSplitReach : 0;
  if (!o.untangle) return 1 + split;
  return (o.project || o.carve ? kUntangleRing : 1 + kCrossingReach * kDualUntangleRounds) + split;
}

int flag_reach(const LocalBrickOptions& o, double largest, const std::array<int, 3>& dims) {
  const double gather =
      std::max({o.local.reach, o.local.empty_cell_reach,
                o.project ? std::max(o.projection.radius, o.projection.wide_radius) : 0.0});
  return int(std::ceil(gather + largest)) + 2 + edge_ring(o) +
         (local_thin_parts(o, dims) ? kThinPartReach : 0);
}

}  // namespace detail

using detail::carving_band;
using detail::edge_ring;
using detail::flag_reach;
using detail::largest_in_spacings;

void require_nameable(const std::array<int, 3>& dims, const LocalBrickOptions& options) {
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
  return std::max(points, int(std::ceil(carving_band(options, dims))) + 2 + edge_ring(options));
}

double local_values_reach(const LocalBrickOptions& options, const std::array<int, 3>& dims) {
  return std::max(largest_in_spacings(options, dims), carving_band(options, dims));
}

}  // namespace sdfcontour
