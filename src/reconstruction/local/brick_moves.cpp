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

}  // namespace sdfcontour::detail
