#include "sdfcontour/reconstruction/adaptivity.h"

#include <cmath>
#include <string>
#include <vector>

#include "reconstruction/adaptivity/brick_merging.h"
#include "reconstruction/adaptivity/surface_fit.h"
#include "reconstruction/point_cubes.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour {

namespace {

// Freezes the vertices of `mesh` (the input) within kFrozenReach spacings of the vertices of
// `merged`'s triangles that cross: returns whether any vertex was newly frozen.
constexpr double kFrozenReach = 3;
// Rounds of freezing at most.
constexpr int kFreezeRounds = 4;
bool freeze_around_crossings(const Mesh& mesh, const Mesh& merged, const std::vector<int>& source,
                             double h, std::vector<char>& frozen) {
  const auto pairs = self_intersecting_triangles(merged);
  if (pairs.empty()) return false;
  std::vector<char> crossing(std::size_t(merged.vertices.rows()), 0);
  for (const auto& [s, t] : pairs)
    for (int k = 0; k < 3; ++k)
      crossing[std::size_t(merged.triangles(s, k))] =
          crossing[std::size_t(merged.triangles(t, k))] = 1;
  const detail::PointCubes cubes(mesh.vertices, kFrozenReach * h);
  bool changed = false;
  for (std::size_t v = 0; v < crossing.size(); ++v) {
    if (!crossing[v]) continue;
    changed |= !frozen[std::size_t(source[v])];
    frozen[std::size_t(source[v])] = 1;
    const Eigen::Vector3d p = merged.vertices.row(Eigen::Index(v)).transpose();
    cubes.for_each_near(p, [&](int u) {
      if (!frozen[std::size_t(u)] &&
          (mesh.vertices.row(u).transpose() - p).norm() <= kFrozenReach * h)
        frozen[std::size_t(u)] = 1, changed = true;
    });
  }
  return changed;
}

}  // namespace

Mesh adapt_mesh(const Mesh& mesh, const PointMatrix& points, const PointMatrix& normals,
                double spacing, const AdaptivityOptions& options, AdaptivityStats* stats) {
  if (points.rows() != normals.rows())
    throw Error("adaptivity: " + std::to_string(points.rows()) + " points but " +
                std::to_string(normals.rows()) + " normals");
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error("adaptivity: the spacing must be positive");
  if (!(options.tolerance >= 0 && options.tolerance <= 10))
    throw Error("adaptivity: the tolerance must lie in [0, 10] spacings");
  if (!(options.max_normal_turn > 0 && options.max_normal_turn <= 180))
    throw Error("adaptivity: the normal turn must lie in (0, 180] degrees");
  if (options.brick_spacings < 0 && options.brick_spacings != AdaptivityOptions::kAutoBricks)
    throw Error("adaptivity: the brick size must not be negative (but for -1: auto)");
  if (options.fit_rounds < 0 || options.fit_rounds > 100)
    throw Error("adaptivity: the fit's rounds must lie in [0, 100]");
  AdaptivityStats s;
  s.triangles_before = s.triangles_after = long(mesh.triangles.rows());
  if (options.tolerance == 0 || mesh.triangles.rows() == 0) {
    if (stats) *stats = s;
    return mesh;
  }
  const std::vector<detail::MergeQuadric> quadrics =
      detail::vertex_quadrics(mesh, points, normals, spacing);
  // Merges that make the mesh cross itself are undone by merging again with the vertices around
  // the crossings frozen: the input's own triangles stay there.
  std::vector<char> frozen(std::size_t(mesh.vertices.rows()), 0);
  std::vector<int> source(frozen.size());
  for (std::size_t v = 0; v < source.size(); ++v) source[v] = int(v);
  const detail::CollapseLimits limits{spacing, options.tolerance, options.max_normal_turn};
  // Bricks on a lattice from the mesh's lowest corner; 0 spacings: one brick holds it all.
  const Eigen::Vector3d origin = mesh.vertices.colwise().minCoeff().transpose();
  const double extent = (mesh.vertices.colwise().maxCoeff().transpose() - origin).maxCoeff();
  // (Auto: bricks of 64 would leave a mesh that spans at most 64 spacings whole, on one core.)
  int bricks = options.brick_spacings;
  if (bricks == AdaptivityOptions::kAutoBricks) bricks = extent <= 64 * spacing ? 32 : 64;
  const double side = bricks > 0 ? bricks * spacing : 2 * extent + spacing;
  detail::MergeState state;
  for (int round = 0;; ++round) {
    state = {mesh, quadrics, frozen, source};
    // Every seam of the first pass lies inside a brick of the second, shifted by half a brick.
    s.merges = detail::merge_in_bricks(state, origin, side, 0.0, limits);
    if (bricks > 0) s.merges += detail::merge_in_bricks(state, origin, side, 0.5, limits);
    if (round == kFreezeRounds ||
        !freeze_around_crossings(mesh, state.mesh, state.source, spacing, frozen))
      break;
    // The input's own crossings (the cube's at 128^3) stay as they are, so that the rounds chase
    // only new ones. Searched only here: most inputs have none, and the search over the input
    // took 1.05 s of bunny 256^3's 9.8 s of merging.
    if (round == 0) freeze_around_crossings(mesh, mesh, source, spacing, frozen);
    ++s.freeze_rounds;
  }
  Mesh out = std::move(state.mesh);
  if (options.fit_rounds > 0) {
    // The frozen regions keep the input's triangles where merging made the mesh cross; corners
    // stay where their contact points put them.
    std::vector<char> fixed(std::size_t(out.vertices.rows()), 0);
    for (std::size_t v = 0; v < fixed.size(); ++v)
      fixed[v] = state.frozen[v] || state.quadrics[v].pinned;
    detail::SurfaceFitOptions fit;
    fit.rounds = options.fit_rounds;
    s.fitted_vertices = detail::fit_merged_vertices(out, mesh, fixed, spacing, fit);
  }
  s.triangles_after = long(out.triangles.rows());
  if (stats) *stats = s;
  return out;
}

}  // namespace sdfcontour
