// A brick's moves of its mesh after the projection (brick_moves.h).
#include "reconstruction/local/brick_moves.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "reconstruction/carving_internal.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::detail {

double carving_band(const LocalBrickOptions& o, const std::array<int, 3>& dims) {
  return o.carve ? auto_carving_band(o.band, *std::max_element(dims.begin(), dims.end())) : 0.0;
}

// The samples whose balls carve the mesh: the band's own (not its margin), or the wider
// carving band's.
Samples carving_samples(const GridView& block, const BandSamples& band,
                        const LocalBrickOptions& o) {
  if (carving_band(o, block.whole_dims()) > 0) {
    BandOptions wide = o.band;
    wide.band = carving_band(o, block.whole_dims());
    wide.margin = 0;
    try {
      return core_samples(select_band(block, wide));
    } catch (const InternalError&) {
      throw;
    } catch (const Cancelled&) {
      throw;
    } catch (const Error&) {
      return Samples();
    }
  }
  return core_samples(band);
}

// Rounds of moving the nearest feature (triangle, edge or vertex) of each band sample within a
// spacing of the surface that lies on the wrong side of the mesh, along its normal, so that the
// sample lies on its own side, kSideMargin |value| beyond it (sphere_carving.h's triangle rounds,
// for the samples' sides alone; moves of more than kLongestSideMove spacings are not made).
constexpr double kSideMargin = 0.1;

// Flags, per sample, whether it lies within `reach` of a flagged vertex (cubes of side reach).
std::vector<char> samples_near(const PointMatrix& samples, const PointMatrix& V,
                               const std::vector<char>& flagged, double reach) {
  std::vector<std::array<long, 3>> cubes;
  auto cube = [&](const Eigen::Vector3d& p) {
    return std::array<long, 3>{long(std::floor(p[0] / reach)), long(std::floor(p[1] / reach)),
                               long(std::floor(p[2] / reach))};
  };
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    if (flagged[std::size_t(v)]) cubes.push_back(cube(V.row(v).transpose()));
  std::sort(cubes.begin(), cubes.end());
  cubes.erase(std::unique(cubes.begin(), cubes.end()), cubes.end());
  std::vector<char> out(std::size_t(samples.rows()), 0);
  tbb::parallel_for(Eigen::Index(0), samples.rows(), [&](Eigen::Index i) {
    const auto c = cube(samples.row(i).transpose());
    for (long dx = -1; dx <= 1 && !out[std::size_t(i)]; ++dx)
      for (long dy = -1; dy <= 1 && !out[std::size_t(i)]; ++dy)
        for (long dz = -1; dz <= 1 && !out[std::size_t(i)]; ++dz)
          out[std::size_t(i)] = std::binary_search(
              cubes.begin(), cubes.end(), std::array<long, 3>{c[0] + dx, c[1] + dy, c[2] + dz});
  });
  return out;
}

void put_samples_on_their_sides(Mesh& mesh, const BandSamples& band, double h, int rounds,
                                const std::vector<char>* near_vertices) {
  std::vector<char> nearby;
  if (near_vertices)
    nearby = samples_near(band.samples.points, mesh.vertices, *near_vertices, 2 * h);
  std::vector<int> near;
  for (Eigen::Index i = 0; i < band.samples.values.size(); ++i)
    if (band.core[std::size_t(i)] && std::abs(band.samples.values[i]) <= h &&
        (!near_vertices || nearby[std::size_t(i)]))
      near.push_back(int(i));
  if (near.empty() || mesh.triangles.rows() == 0) return;
  const detail::VertexTriangles around(mesh);
  // The feature moves until the sample is just on its side (kSideMargin of its |value| beyond),
  // not its whole ball away: a smooth surface moved further would leave the samples next to it.
  const Eigen::VectorXd margins = kSideMargin * band.samples.values;
  for (int round = 0; round < rounds; ++round) {
    const detail::SideCheck found = detail::check_sample_sides(
        mesh, around, band.samples.points, margins, near, INFINITY, kLongestSideMove * h);
    if (found.wrong_side == 0) return;
    mesh.vertices += found.moves;
  }
}

// The vertices of `mesh` whose band samples are no distances to it, moved onto the block's
// tricubic zero set; `stay` (if given: empty or one flag per vertex) gains them. With
// `fallback` (one position per vertex), those that the interpolant could not move start again
// from there.
void refine_vertices_on_zero_set(const GridView& block, const BandSamples& band,
                                 const LocalBrickOptions& options, Mesh& mesh,
                                 const std::vector<char>* fixed, std::vector<char>* stay,
                                 const PointMatrix* fallback) {
  ZeroSetRefinementOptions zero_set = options.zero_set;
  zero_set.truncation =
      std::min(zero_set.truncation, grid_truncation(band.truncation, options.band.value_scale));
  std::vector<char> moved, flagged;
  const ZeroSetRefinementStats stats = refine_where_values_are_no_distances(
      mesh, band.samples, block, zero_set, fixed, &moved, &flagged);
  if (fallback && stats.moved < stats.flagged) {
    std::vector<char> again(flagged.size(), 0), moved_again;
    PointMatrix starts = *fallback;
    for (std::size_t v = 0; v < flagged.size(); ++v)
      again[v] = char(flagged[v] && !moved[v] && starts.row(Eigen::Index(v)).allFinite());
    refine_on_zero_set(starts, again, block, zero_set, &moved_again);
    for (std::size_t v = 0; v < moved.size(); ++v)
      if (moved_again[v]) {
        mesh.vertices.row(Eigen::Index(v)) = starts.row(Eigen::Index(v));
        moved[v] = 1;
      }
  }
  if (!stay || std::none_of(moved.begin(), moved.end(), [](char m) { return m != 0; })) return;
  if (stay->empty()) stay->assign(moved.size(), 0);
  for (std::size_t v = 0; v < moved.size(); ++v) (*stay)[v] = char((*stay)[v] || moved[v]);
}

}  // namespace sdfcontour::detail
