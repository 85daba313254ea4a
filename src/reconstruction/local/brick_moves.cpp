// A brick's moves of its mesh after the projection (brick_moves.h).
#include "brick_moves.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "../../carving_internal.h"
#include "sdfcontour/self_intersections.h"

namespace sdfcontour::detail {

// Carving's balls reach this many spacings on a coarse grid with the automatic band (as
// ContourOptions' carving: the wider band lowers L1, the grid being coarse); 0: the band's.
constexpr double kCarvingBand = 16;
double carving_band(const LocalBrickOptions& o, const std::array<int, 3>& dims) {
  return o.carve && o.band.band == 0 && *std::max_element(dims.begin(), dims.end()) < 128
             ? kCarvingBand
             : 0.0;
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

void put_samples_on_their_sides(Mesh& mesh, const BandSamples& band, double h, int rounds) {
  std::vector<int> near;
  for (Eigen::Index i = 0; i < band.samples.values.size(); ++i)
    if (band.core[std::size_t(i)] && std::abs(band.samples.values[i]) <= h) near.push_back(int(i));
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

// Rounds (kUntangleRounds) of moving back to `before` (the positions before projection and
// carving) every moved vertex of a triangle that crosses another; each round after the first
// tests the triangles the last one changed. Every decision of a round is taken from the
// positions the round started with. (Crossings the reconstruction itself makes stay.)
void undo_crossing_moves(Mesh& mesh, const PointMatrix& before, int rounds) {
  std::vector<char> watch;
  for (int round = 0; round < rounds; ++round) {
    const auto pairs = self_intersecting_triangles(mesh, round == 0 ? nullptr : &watch);
    std::vector<char> back(std::size_t(mesh.vertices.rows()), 0);
    bool any = false;
    for (const auto& [s, t] : pairs)
      for (const int tri : {s, t})
        for (int c = 0; c < 3; ++c) {
          const int v = mesh.triangles(tri, c);
          if (mesh.vertices.row(v) != before.row(v)) back[std::size_t(v)] = 1, any = true;
        }
    if (!any) return;
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
      if (back[std::size_t(v)]) mesh.vertices.row(v) = before.row(v);
    watch.assign(std::size_t(mesh.triangles.rows()), 0);
    for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
      for (int c = 0; c < 3; ++c) watch[std::size_t(t)] |= back[std::size_t(mesh.triangles(t, c))];
  }
}

}  // namespace sdfcontour::detail
