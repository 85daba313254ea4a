// A brick's moves of its mesh after the projection (brick_moves.h).
#include "reconstruction/local/brick_moves.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "reconstruction/carving_internal.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::detail {

double carving_band(const LocalBrickOptions& o, const std::array<int, 3>& dims) {
  return o.carve ? auto_carving_band(o.band, *std::max_element(dims.begin(), dims.end())) : 0.0;
}

std::optional<BandSamples> wider_carving_band(const GridView& block, const LocalBrickOptions& o) {
  if (!(carving_band(o, block.whole_dims()) > 0)) return std::nullopt;
  BandOptions wide = o.band;
  wide.band = carving_band(o, block.whole_dims());
  wide.margin = 0;
  try {
    return select_band(block, wide);
  } catch (const InternalError&) {
    throw;
  } catch (const Cancelled&) {
    throw;
  } catch (const Error&) {
    return BandSamples();
  }
}

// Rounds of moving the nearest feature (triangle, edge or vertex) of each band sample within a
// spacing of the surface that lies on the wrong side of the mesh, along its normal, so that the
// sample lies on its own side, kSideMargin |value| beyond it (sphere_carving.h's triangle rounds,
// for the samples' sides alone; moves of more than kLongestSideMove spacings are not made).
constexpr double kSideMargin = 0.1;

// See put_samples_on_their_sides.
constexpr double kNearbyTriangles = 2;

// Flags, per sample, whether it lies within `reach` of a flagged vertex (cubes of side reach): its
// cube is one of the flagged vertices' cubes or their neighbours, which are listed once, so that
// each sample searches once.
std::vector<char> samples_near(const PointMatrix& samples, const PointMatrix& V,
                               const std::vector<char>& flagged, double reach) {
  using Cube = std::array<long, 3>;
  auto cube = [&](const Eigen::Vector3d& p) {
    return Cube{long(std::floor(p[0] / reach)), long(std::floor(p[1] / reach)),
                long(std::floor(p[2] / reach))};
  };
  std::vector<Cube> cubes;
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    if (flagged[std::size_t(v)]) cubes.push_back(cube(V.row(v).transpose()));
  std::sort(cubes.begin(), cubes.end());
  cubes.erase(std::unique(cubes.begin(), cubes.end()), cubes.end());
  std::vector<Cube> around;
  around.reserve(27 * cubes.size());
  for (const Cube& c : cubes)
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) around.push_back({c[0] + dx, c[1] + dy, c[2] + dz});
  tbb::parallel_sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  std::vector<char> out(std::size_t(samples.rows()), 0);
  if (around.empty()) return out;
  tbb::parallel_for(Eigen::Index(0), samples.rows(), [&](Eigen::Index i) {
    out[std::size_t(i)] =
        std::binary_search(around.begin(), around.end(), cube(samples.row(i).transpose()));
  });
  return out;
}

// The triangles of `mesh` that come within `reach` of one of the samples `which`: those with a
// vertex within reach plus the longest edge of one.
std::vector<int> triangles_near_samples(const Mesh& mesh, const PointMatrix& points,
                                        const std::vector<int>& which, double reach) {
  const TriangleMatrix& F = mesh.triangles;
  const PointMatrix& V = mesh.vertices;
  const double longest = tbb::parallel_reduce(
      tbb::blocked_range<Eigen::Index>(0, F.rows()), 0.0,
      [&](const tbb::blocked_range<Eigen::Index>& r, double most) {
        for (Eigen::Index t = r.begin(); t < r.end(); ++t)
          for (int c = 0; c < 3; ++c)
            most = std::max(most, (V.row(F(t, c)) - V.row(F(t, (c + 1) % 3))).squaredNorm());
        return most;
      },
      [](double a, double b) { return std::max(a, b); });
  PointMatrix at(Eigen::Index(which.size()), 3);
  for (std::size_t q = 0; q < which.size(); ++q) at.row(Eigen::Index(q)) = points.row(which[q]);
  const std::vector<char> near =
      samples_near(V, at, std::vector<char>(which.size(), 1), reach + std::sqrt(longest));
  std::vector<int> out;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    if (near[std::size_t(F(t, 0))] || near[std::size_t(F(t, 1))] || near[std::size_t(F(t, 2))])
      out.push_back(int(t));
  return out;
}

void put_samples_on_their_sides(Mesh& mesh, const BandSamples& band, double h, int rounds,
                                const std::vector<char>* near_vertices) {
  std::vector<int> near;
  for (Eigen::Index i = 0; i < band.samples.values.size(); ++i)
    if (band.core[std::size_t(i)] && std::abs(band.samples.values[i]) <= h) near.push_back(int(i));
  if (near_vertices) {
    // (Asked of these samples alone: the band holds many times more.)
    PointMatrix at(Eigen::Index(near.size()), 3);
    for (std::size_t q = 0; q < near.size(); ++q)
      at.row(Eigen::Index(q)) = band.samples.points.row(near[q]);
    const std::vector<char> nearby = samples_near(at, mesh.vertices, *near_vertices, 2 * h);
    std::size_t kept = 0;
    for (std::size_t q = 0; q < near.size(); ++q)
      if (nearby[q]) near[kept++] = near[q];
    near.resize(kept);
  }
  if (near.empty() || mesh.triangles.rows() == 0) return;
  const detail::VertexTriangles around(mesh);
  // The feature moves until the sample is just on its side (kSideMargin of its |value| beyond),
  // not its whole ball away: a smooth surface moved further would leave the samples next to it.
  const Eigen::VectorXd margins = kSideMargin * band.samples.values;
  // A few samples (near given vertices) search, in the first round, the triangles within
  // kNearbyTriangles spacings of them alone: exact wherever each one's nearest point lies within
  // that (else all are searched).
  const double reach = kNearbyTriangles * h;
  const std::vector<int> among =
      near_vertices ? triangles_near_samples(mesh, band.samples.points, near, reach)
                    : std::vector<int>();
  for (int round = 0; round < rounds; ++round) {
    const bool nearby_only = round == 0 && !among.empty();
    detail::SideCheck found =
        detail::check_sample_sides(mesh, around, band.samples.points, margins, near, INFINITY,
                                   kLongestSideMove * h, nearby_only ? &among : nullptr);
    if (nearby_only && !(found.farthest <= reach))
      found = detail::check_sample_sides(mesh, around, band.samples.points, margins, near, INFINITY,
                                         kLongestSideMove * h);
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
