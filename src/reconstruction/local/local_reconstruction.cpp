// The local reconstruction (local_reconstruction.h): active cells and their polygons, a vertex per
// polygon from the contact points near the cell, a quad per sign-changing grid edge.
#include "sdfcontour/reconstruction/local_reconstruction.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "extraction/cube_polygons.h"
#include "reconstruction/local/cell_quadric.h"
#include "reconstruction/local/edge_fans.h"
#include "reconstruction/local/keyed_local_mesh.h"
#include "reconstruction/local/surface_cells.h"
#include "reconstruction/local/vertex_placement.h"

namespace sdfcontour {

namespace {

// A cell's crossings whose normals turn by more than this (the cosine of the widest pair's
// angle under it) straddle a feature; nearly parallel ones lie on a smooth patch, where two
// distant points' planes meet at a false edge (a sphere clamped at 1.2 spacings at 40^3: a vertex
// 0.29 h off, against marching cubes' 0.01 h).
constexpr double kCrossingsTurn = 0.985;  // 10 degrees

bool crossings_turn(const std::vector<detail::TangentPlane>& crossings) {
  for (std::size_t a = 0; a < crossings.size(); ++a)
    for (std::size_t b = a + 1; b < crossings.size(); ++b)
      if (crossings[a].normal.dot(crossings[b].normal) < kCrossingsTurn) return true;
  return false;
}

using detail::ActiveCell;
using detail::SurfaceCells;
using detail::TangentPlane;
using detail::VertexResult;

// Contact points sorted by the cell that holds them (ties by position, so the order of the input
// rows does not matter), for the gathering around each cell.
struct BinnedPoints {
  std::vector<std::int64_t> cell;  // ascending
  std::vector<int> row;            // the point's row in the input
  // Per column of cells (i, j): where its keys start in `cell`, then the end: a search then reads
  // one column's few points, not every point (each step of which missed the cache).
  std::vector<int> column_start;
};

BinnedPoints bin_points(const SurfaceCells& cells, const PointMatrix& points) {
  const Eigen::Index k = points.rows();
  std::vector<std::pair<std::int64_t, int>> keyed(std::size_t(k), {0, 0});
  tbb::parallel_for(Eigen::Index(0), k, [&](Eigen::Index r) {
    keyed[std::size_t(r)] = {cells.key_of_point(points.row(r).transpose()), int(r)};
  });
  tbb::parallel_sort(keyed.begin(), keyed.end(), [&](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    const auto pa = points.row(a.second), pb = points.row(b.second);
    for (int d = 0; d < 3; ++d)
      if (pa[d] != pb[d]) return pa[d] < pb[d];
    return a.second < b.second;
  });
  BinnedPoints out;
  out.cell.reserve(keyed.size());
  out.row.reserve(keyed.size());
  for (const auto& [key, r] : keyed) {
    out.cell.push_back(key);
    out.row.push_back(r);
  }
  const std::size_t columns = std::size_t(cells.cell_dims[0]) * std::size_t(cells.cell_dims[1]);
  out.column_start.resize(columns + 1);
  tbb::parallel_for(std::size_t(0), columns + 1, [&](std::size_t column) {
    out.column_start[column] = int(std::lower_bound(out.cell.begin(), out.cell.end(),
                                                    std::int64_t(column) * cells.cell_dims[2]) -
                                   out.cell.begin());
  });
  return out;
}

// The rows of the contact points in the cell grown by `reach` (in the grid's units per axis).
void gather_points(const SurfaceCells& cells, const BinnedPoints& bins, const PointMatrix& points,
                   const std::array<int, 3>& at, const Eigen::Vector3d& reach,
                   std::vector<int>& rows) {
  rows.clear();
  const Eigen::Vector3d lo = cells.corner(at) - reach;
  const Eigen::Vector3d hi = cells.corner(at) + cells.spacing + reach;
  std::array<int, 3> ring;
  for (int a = 0; a < 3; ++a)
    ring[std::size_t(a)] = std::max(1, int(std::ceil(reach[a] / cells.spacing[a])));
  // The cells along k are consecutive keys: one search per column of them.
  const int k0 = std::max(0, at[2] - ring[2]),
            k1 = std::min(cells.cell_dims[2] - 1, at[2] + ring[2]);
  if (k0 > k1) return;
  for (int di = -ring[0]; di <= ring[0]; ++di)
    for (int dj = -ring[1]; dj <= ring[1]; ++dj) {
      const std::array<int, 3> first_cell{at[0] + di, at[1] + dj, k0};
      if (!cells.contains_cell(first_cell)) continue;
      const std::int64_t last_key = cells.key({at[0] + di, at[1] + dj, k1});
      const std::size_t column =
          std::size_t(first_cell[0]) * std::size_t(cells.cell_dims[1]) + std::size_t(first_cell[1]);
      auto it = std::lower_bound(bins.cell.begin() + bins.column_start[column],
                                 bins.cell.begin() + bins.column_start[column + 1],
                                 cells.key(first_cell));
      for (; it != bins.cell.end() && *it <= last_key; ++it) {
        const int r = bins.row[std::size_t(it - bins.cell.begin())];
        const Eigen::Vector3d p = points.row(r).transpose();
        if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) rows.push_back(r);
      }
    }
}

// Where the polygon's contact points come from in a cell with several polygons: each point goes
// to the polygon with a crossing nearest to it, among those whose outward direction its normal
// agrees with.
int polygon_of_point(const detail::CellPolygons& polys, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& n) {
  int best = -1;
  double best_distance = 0;
  for (int q = 0; q < polys.count; ++q) {
    if (n.dot(polys.outward[q]) <= 0) continue;
    for (int e = polys.first_crossing[q]; e < polys.first_crossing[q + 1]; ++e) {
      const double d = (polys.crossing[e] - p).squaredNorm();
      if (best < 0 || d < best_distance) best = q, best_distance = d;
    }
  }
  return best;
}

// The distance from p (in cell `at`) to the zero set of the cell's trilinear interpolant, to
// first order: |value| / |gradient| at p.
double trilinear_miss(const SurfaceCells& cells, const std::array<int, 3>& at,
                      const Eigen::Vector3d& p) {
  const Eigen::Vector3d t =
      ((p - cells.corner(at)).array() / cells.spacing.array()).min(1.0).max(0.0).matrix();
  double value = 0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  for (int c = 0; c < 8; ++c) {
    const double f = detail::value_at(cells.grid, detail::corner_of(at, c));
    double w = 1;
    Eigen::Vector3d dw = Eigen::Vector3d::Ones();
    for (int d = 0; d < 3; ++d) {
      const bool high = c >> d & 1;
      const double wd = high ? t[d] : 1 - t[d];
      w *= wd;
      for (int e = 0; e < 3; ++e) dw[e] *= e == d ? (high ? 1 : -1) / cells.spacing[d] : wd;
    }
    value += w * f;
    gradient += dw * f;
  }
  const double g = gradient.norm();
  return g > 0 ? std::abs(value) / g : INFINITY;
}

// Every polygon's vertex, in cell order then polygon order.
PointMatrix cell_vertices(const SurfaceCells& cells, const PointMatrix& points,
                          const PointMatrix& normals, const Eigen::VectorXd& weights,
                          const LocalReconstructionOptions& options,
                          LocalReconstructionStats& stats, std::vector<std::array<char, 4>>& flags,
                          PointMatrix& crossing_means) {
  const BinnedPoints bins = bin_points(cells, points);
  const Eigen::Vector3d reach = options.reach * cells.spacing;
  const double h = cells.spacing.maxCoeff();
  PointMatrix vertices(cells.vertex_count(), 3);
  crossing_means.resize(vertices.rows(), 3);
  flags.assign(std::size_t(vertices.rows()), {0, 0, 0, 0});
  tbb::parallel_for(std::size_t(0), cells.active.size(), [&](std::size_t c) {
    const ActiveCell& cell = cells.active[c];
    const std::array<int, 3> at = cells.cell_of_key(cell.key);
    const detail::CellPolygons polys = cells.polygons(cell);
    std::vector<int> rows;
    auto planes_near = [&](const Eigen::Vector3d& reach_here) {
      gather_points(cells, bins, points, at, reach_here, rows);
      std::vector<std::vector<TangentPlane>> planes(std::size_t(polys.count));
      for (int r : rows) {
        const Eigen::Vector3d p = points.row(r).transpose(), n = normals.row(r).transpose();
        const int q = polys.count == 1 ? (n.dot(polys.outward[0]) > 0 ? 0 : -1)
                                       : polygon_of_point(polys, p, n);
        if (q >= 0) planes[std::size_t(q)].push_back({p, n, weights.size() ? weights[r] : 1.0});
      }
      return planes;
    };
    const std::vector<std::vector<TangentPlane>> planes = planes_near(reach);
    std::vector<std::vector<TangentPlane>> wide;  // gathered farther, for polygons short of points
    const Eigen::Vector3d lo = cells.corner(at), hi = lo + cells.spacing;
    for (int q = 0; q < polys.count; ++q) {
      std::vector<TangentPlane> crossings;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int e = polys.first_crossing[q]; e < polys.first_crossing[q + 1]; ++e) {
        crossings.push_back({polys.crossing[e], polys.crossing_normal[e]});
        mean += polys.crossing[e];
      }
      crossing_means.row(cell.first_vertex + q) = (mean / double(crossings.size())).transpose();
      VertexResult v = place_vertex(planes[std::size_t(q)], crossings, lo, hi, h, options);
      const std::vector<TangentPlane>* placed_from = &planes[std::size_t(q)];  // v's planes
      // The vertex from the planes gathered farther (empty_cell_reach) where those planes meet
      // at a corner beyond the cell: on the corner's edges that cross the cell, if any.
      const bool gather_wide = options.empty_cell_reach > options.reach;
      auto wide_planes = [&]() -> const std::vector<TangentPlane>& {
        if (wide.empty()) wide = planes_near(options.empty_cell_reach * cells.spacing);
        return wide[std::size_t(q)];
      };
      auto corner_edge = [&](const VertexResult& w) -> std::optional<VertexResult> {
        if (!w.corner_beyond) return std::nullopt;
        return corner_edge_vertex(wide_planes(), *w.corner_beyond, lo, hi, h, options);
      };
      // A feature from fewer planes than kFewFeaturePlanes may be no feature: a point at a
      // corner has a normal anywhere in the corner's cone, and with one other plane it makes an
      // edge that is not there (the built-in box at 40^3, band 3: a vertex 0.18 h off).
      const bool few_for_feature =
          v.feature && !v.corner && planes[std::size_t(q)].size() < detail::kFewFeaturePlanes;
      if ((v.from_crossings || few_for_feature) && gather_wide) {
        // Only a feature (edge or corner) in the cell is taken from farther points: a smooth
        // patch without points of its own (a thin part, a noisy field) keeps its crossings, as
        // does a feature beyond the cell (penguin 32^3: 16% higher L1 with those).
        const VertexResult w = place_vertex(wide_planes(), crossings, lo, hi, h, options);
        if (v.from_crossings && !w.from_crossings && w.feature && w.fitted &&
            crossings_turn(crossings)) {
          v = w;
          v.position = *w.fitted;
          placed_from = &wide_planes();
        } else if (auto e = corner_edge(w)) {
          v = *e;
        }
      }
      // (Not at a feature: there the interpolant itself cuts the corner.)
      if (!v.from_crossings && !v.feature && options.max_field_miss > 0 &&
          trilinear_miss(cells, at, v.position) > options.max_field_miss * h) {
        v = place_vertex({}, crossings, lo, hi, h, options);
        v.field_miss = true;
        // One plane next to a corner, its normal bent (the built-in box at 64^3, band 4: the
        // crossings 0.16 h off the edge).
        if (gather_wide)
          if (auto e = corner_edge(place_vertex(wide_planes(), crossings, lo, hi, h, options)))
            v = *e;
      }
      if (v.clamped && !v.from_crossings) {
        // A feature just outside the cell (planes from beyond its sides): the cell's own points.
        std::vector<TangentPlane> own;
        for (const TangentPlane& t : planes[std::size_t(q)])
          if ((t.point.array() >= lo.array()).all() && (t.point.array() <= hi.array()).all())
            own.push_back(t);
        if (int(own.size()) >= options.min_points) {
          const VertexResult w = place_vertex(own, crossings, lo, hi, h, options);
          if (!w.clamped) v = w;
        }
      }
      // The clamped vertex or the one among the cell's crossings, whichever the grid's values
      // put nearer the surface (vertex_placement.h's within_crossings).
      if (v.crossings_box) {
        const Eigen::Vector3d w = within_crossings(*placed_from, *v.crossings_box, h, options);
        if (trilinear_miss(cells, at, w) < trilinear_miss(cells, at, v.position)) v.position = w;
      }
      // (A narrow cell's smooth patch whose plane misses it: narrow_cells.)
      if (options.narrow_cells && v.clamped && !v.feature && !v.from_crossings)
        v = place_vertex({}, crossings, lo, hi, h, options);
      const Eigen::Index id = cell.first_vertex + q;
      vertices.row(id) = v.position.transpose();
      flags[std::size_t(id)] = {char(v.from_crossings), char(v.feature ? 1 + v.corner : 0),
                                char(v.clamped), char(v.field_miss)};
    }
  });
  for (const auto& f : flags) {
    stats.crossing_cells += f[0];
    stats.feature_vertices += f[1] != 0;
    stats.clamped += f[2];
    stats.field_misses += f[3];
  }
  return vertices;
}

// The two triangles of quad q (counter-clockwise seen from outside): split along the diagonal
// whose triangles turn least from each other, so that a quad bent over an edge folds along it.
void split_quad(const PointMatrix& v, const std::array<int, 4>& q, int* out) {
  auto normal = [&](int a, int b, int c) {
    const Eigen::Vector3d pa = v.row(a).transpose();
    return Eigen::Vector3d((v.row(b).transpose() - pa).cross(v.row(c).transpose() - pa));
  };
  auto cosine = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const double n = a.norm() * b.norm();
    return n > 0 ? a.dot(b) / n : -1.0;
  };
  const double c02 = cosine(normal(q[0], q[1], q[2]), normal(q[0], q[2], q[3]));
  const double c13 = cosine(normal(q[0], q[1], q[3]), normal(q[1], q[2], q[3]));
  const std::array<int, 6> along02{q[0], q[1], q[2], q[0], q[2], q[3]};
  const std::array<int, 6> along13{q[0], q[1], q[3], q[1], q[2], q[3]};
  const auto& pick = c13 > c02 ? along13 : along02;
  std::copy(pick.begin(), pick.end(), out);
}

// A polygon with a segment vertex is fanned from it: its diagonals then join the segment vertex,
// never the two cell vertices it keeps apart.
void fan_from_segment_vertex(const std::array<int, 8>& p, int size, int first_extra, int* out) {
  int apex = 0;
  while (p[std::size_t(apex)] < first_extra) ++apex;
  for (int q = 1; q + 1 < size; ++q) {
    *out++ = p[std::size_t(apex)];
    *out++ = p[std::size_t((apex + q) % size)];
    *out++ = p[std::size_t((apex + q + 1) % size)];
  }
}

// first_edge >= 0: polygon i is fanned from vertex first_edge + i, on its grid edge, into as many
// triangles as it has sides.
void triangulate_polygons(const detail::DualPolygons& polygons, int first_extra, int first_edge,
                          detail::KeyedLocalMesh& keyed) {
  Mesh& mesh = keyed.mesh;
  const bool fans = first_edge >= 0;
  std::vector<Eigen::Index> first(polygons.size.size() + 1, 0);
  for (std::size_t i = 0; i < polygons.size.size(); ++i)
    first[i + 1] = first[i] + polygons.size[i] - (fans ? 0 : 2);
  mesh.triangles.resize(first.back(), 3);
  keyed.triangle_edge.resize(std::size_t(first.back()));
  keyed.triangle_rank.resize(std::size_t(first.back()));
  tbb::parallel_for(std::size_t(0), polygons.size.size(), [&](std::size_t i) {
    for (Eigen::Index t = first[i]; t < first[i + 1]; ++t) {
      keyed.triangle_edge[std::size_t(t)] = polygons.edge[i];
      keyed.triangle_rank[std::size_t(t)] = std::uint8_t(t - first[i]);
    }
    int* out = mesh.triangles.data() + 3 * first[i];
    const auto& p = polygons.vertices[i];
    const int k = polygons.size[i];
    if (fans) {
      for (int q = 0; q < k; ++q) {
        *out++ = first_edge + int(i);
        *out++ = p[std::size_t(q)];
        *out++ = p[std::size_t((q + 1) % k)];
      }
    } else if (k == 4)
      split_quad(mesh.vertices, {p[0], p[1], p[2], p[3]}, out);
    else
      fan_from_segment_vertex(p, polygons.size[i], first_extra, out);
  });
}

}  // namespace

Mesh local_reconstruction(const GridView& grid, const PointMatrix& points,
                          const PointMatrix& normals, const LocalReconstructionOptions& options,
                          LocalReconstructionStats* stats_out, const Eigen::VectorXd& depths) {
  return detail::keyed_local_reconstruction(grid, points, normals, options, stats_out, depths).mesh;
}

namespace detail {

KeyedLocalMesh keyed_local_reconstruction(const GridView& grid, const PointMatrix& points,
                                          const PointMatrix& normals,
                                          const LocalReconstructionOptions& options,
                                          LocalReconstructionStats* stats_out,
                                          const Eigen::VectorXd& depths,
                                          const std::array<std::array<int, 3>, 2>* cell_box) {
  if (points.rows() != normals.rows())
    throw Error("local reconstruction: " + std::to_string(points.rows()) + " contact points but " +
                std::to_string(normals.rows()) + " normals");
  if (!points.allFinite() || !normals.allFinite())
    throw Error("local reconstruction: contact points or normals are not finite");
  if (!(options.reach >= 0 && options.reach <= 1))
    throw Error("local reconstruction: reach must lie in [0, 1] spacings");
  if (!(options.empty_cell_reach >= 0 && options.empty_cell_reach <= 4))
    throw Error("local reconstruction: empty_cell_reach must lie in [0, 4] spacings");
  if (depths.size() != 0 && depths.size() != points.rows())
    throw Error("local reconstruction: depths must be empty or one per contact point");
  if (!(options.depth_scale >= 0) || !std::isfinite(options.depth_scale))
    throw Error("local reconstruction: depth_scale must be a non-negative number of spacings");
  LocalReconstructionStats stats;
  const SurfaceCells cells = detail::find_surface_cells(grid, cell_box);
  KeyedLocalMesh keyed;
  Mesh& mesh = keyed.mesh;
  Eigen::VectorXd weights;
  if (depths.size() && options.depth_scale > 0) {
    const double scale = options.depth_scale * grid.spacing().maxCoeff();
    weights = 1 / (1 + (depths.array() / scale).square());
  }
  mesh.vertices = cell_vertices(cells, points, normals, weights, options, stats, keyed.flags,
                                keyed.crossing_means);
  const bool fans = options.edge_fans;
  const detail::DualPolygons polygons = cells.dual_polygons(fans);
  const Eigen::Index cell_vertex_count = mesh.vertices.rows();
  const Eigen::Index first_edge = cell_vertex_count + Eigen::Index(polygons.extra_positions.size());
  mesh.vertices.conservativeResize(
      first_edge + (fans ? Eigen::Index(polygons.edge_point.size()) : 0), 3);
  for (std::size_t e = 0; e < polygons.extra_positions.size(); ++e)
    mesh.vertices.row(cell_vertex_count + Eigen::Index(e)) =
        polygons.extra_positions[e].transpose();
  if (fans)
    for (std::size_t e = 0; e < polygons.edge_point.size(); ++e)
      mesh.vertices.row(first_edge + Eigen::Index(e)) = polygons.edge_point[e].transpose();
  triangulate_polygons(polygons, int(cell_vertex_count), fans ? int(first_edge) : -1, keyed);
  // Global names: 4 * cell + polygon (a cell has at most 4), then the segment vertices.
  keyed.vertex_key.resize(std::size_t(mesh.vertices.rows()));
  for (const ActiveCell& cell : cells.active) {
    const std::uint64_t base = 4 * cells.global_cell(cells.cell_of_key(cell.key));
    for (int q = 0; q < cell.polygon_count; ++q)
      keyed.vertex_key[std::size_t(cell.first_vertex + q)] = base + std::uint64_t(q);
  }
  const detail::VertexKeyBases bases = detail::vertex_key_bases(grid.whole_dims());
  for (std::size_t e = 0; e < polygons.extra_keys.size(); ++e)
    keyed.vertex_key[std::size_t(cell_vertex_count) + e] = bases.segments + polygons.extra_keys[e];
  if (fans)
    for (std::size_t e = 0; e < polygons.edge.size(); ++e)
      keyed.vertex_key[std::size_t(first_edge) + e] = bases.edges + polygons.edge[e];
  stats.cells = long(cells.active.size());
  stats.vertices = long(mesh.vertices.rows());
  for (const ActiveCell& cell : cells.active) stats.split_cells += cell.polygon_count > 1;
  if (stats_out) *stats_out = stats;
  return keyed;
}

}  // namespace detail

}  // namespace sdfcontour
