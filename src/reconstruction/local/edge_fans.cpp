// An edge-fanned mesh's vertices in their regions (edge_fans.h).
#include "reconstruction/local/edge_fans.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "reconstruction/carving_internal.h"
#include "reconstruction/local/brick_ownership.h"
#include "reconstruction/mesh_geometry.h"
#include "sdfcontour/reconstruction/contact_projection.h"

namespace sdfcontour::detail {

namespace {

// A vertex stays this fraction of its cell or edge away from the cell's sides or the samples:
// the vertex placement's own margin, which keeps the argument strict (no two triangles of
// different cells share more than the faces between them).
constexpr double kMargin = 1e-3;

// A face's vertex is made only where its chord crosses the face's plane within this many spacings
// of the face (the vertex is then kept on the face).
constexpr double kFaceReach = 0.25;

// The position on the segment from `start` + [0, h] along `axis` (clamped a margin inside, and
// out of its ends' spheres of radius `from_radius` and `to_radius` where they leave room) where
// the plane through `now`, normal to the move from `was`, meets it; a segment nearly in that
// plane keeps `was`'s place along it. (A plane nearly along the segment met it far off: a vertex
// clamped next to a sample 0.69 h from the surface, armadillo at 512^3.)
double place_along(const Eigen::Vector3d& start, int axis, double h, const Eigen::Vector3d& was,
                   const Eigen::Vector3d& now, double from_radius = 0, double to_radius = 0) {
  const Eigen::Vector3d move = now - was;
  double t = was[axis] - start[axis];
  if (move.norm() > 0 && std::abs(move[axis]) > 0.2 * move.norm())
    t = (now - start).dot(move) / move[axis];
  double from = kMargin * h, to = (1 - kMargin) * h;
  // Out of the ends' spheres where they leave room (they do where the values are distances).
  if (std::max(from, from_radius) <= std::min(to, h - to_radius)) {
    from = std::max(from, from_radius);
    to = std::min(to, h - to_radius);
  }
  return std::clamp(t, from, to);
}

// `now` put into the box [lo, hi]: clamped, then slid along the box's sides that hold it back to
// the plane through `now` normal to its move from `was` (the surface there, as the projection
// found it), where that plane is not nearly parallel to them. A vertex whose fit lies just
// beyond its cell's side stays on the surface, not a clamp's length inside it (a sphere's
// shallow crease at 64^3: 0.085 h).
Eigen::Vector3d slide_into_box(const Eigen::Vector3d& now, const Eigen::Vector3d& was,
                               const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d clamped = now.cwiseMax(lo).cwiseMin(hi);
  const Eigen::Vector3d move = now - was;
  // (Not a fit that lies farther out than a quarter of the cell: its surface passes elsewhere,
  // a finer grid's false thin part, and the slide would run across the cell.)
  if (clamped == now || move.squaredNorm() == 0 ||
      (clamped - now).norm() > 0.25 * (hi - lo).maxCoeff())
    return clamped;
  const Eigen::Vector3d n = move.normalized();
  Eigen::Vector3d kept = clamped;
  for (int round = 0; round < 3; ++round) {
    Eigen::Vector3d along = n;  // the normal within the held sides' planes
    for (int a = 0; a < 3; ++a)
      if (kept[a] == lo[a] || kept[a] == hi[a]) along[a] = 0;
    const double off = n.dot(kept - now), reach = along.squaredNorm();
    if (reach < 0.01 || off == 0) break;
    kept = (kept - off / reach * along).cwiseMax(lo).cwiseMin(hi);
  }
  return kept;
}

// The face between two cells that share one (their vertex keys' cells): its axis and the
// position of its plane; false if the cells share no face.
bool shared_face(std::uint64_t kx, std::uint64_t ky, const std::array<int, 3>& cells,
                 const GridGeometry& grid, int& axis, Eigen::Vector3d& low) {
  const std::array<int, 3> a = grid_point_of(kx / 4, cells), b = grid_point_of(ky / 4, cells);
  axis = -1;
  for (int d = 0; d < 3; ++d) {
    const int diff = std::abs(a[std::size_t(d)] - b[std::size_t(d)]);
    if (diff > 1 || (diff == 1 && axis >= 0)) return false;
    if (diff == 1) axis = d;
  }
  if (axis < 0) return false;
  const Eigen::Vector3d h = grid.spacing();
  for (int d = 0; d < 3; ++d)
    low[d] = grid.bounds.min[d] + std::max(a[std::size_t(d)], b[std::size_t(d)]) * h[d];
  return true;
}

// Where the chord between sub's vertices x and y (of the cells keyed kx and ky) crosses the plane
// of the face between the two cells (shared_face's `axis` and `low`); false if the cells share no
// face or the chord runs along it.
bool chord_crossing(const SubdividedMesh& sub, int x, int y, std::uint64_t kx, std::uint64_t ky,
                    const std::array<int, 3>& cells, const GridGeometry& grid, int& axis,
                    Eigen::Vector3d& low, Eigen::Vector3d& at) {
  const Eigen::Vector3d a = sub.mesh.vertices.row(x).transpose(),
                        b = sub.mesh.vertices.row(y).transpose();
  if (!shared_face(kx, ky, cells, grid, axis, low) || a[axis] == b[axis]) return false;
  at = a + (low[axis] - a[axis]) / (b[axis] - a[axis]) * (b - a);
  return true;
}

}  // namespace

std::vector<std::uint64_t> split_cells(const std::vector<std::uint64_t>& keys,
                                       const std::array<int, 3>& n) {
  const VertexKeyBases bases = vertex_key_bases(n);
  std::vector<std::uint64_t> out;
  for (const std::uint64_t k : keys)  // a second polygon: 4 * cell + 1 and up
    if (k < bases.segments && k % 4 != 0) out.push_back(k / 4);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

VertexKeyBases vertex_key_bases(const std::array<int, 3>& n) {
  VertexKeyBases b;
  const std::uint64_t points = std::uint64_t(n[0]) * std::uint64_t(n[1]) * std::uint64_t(n[2]);
  b.segments = 4 * std::uint64_t(n[0] - 1) * std::uint64_t(n[1] - 1) * std::uint64_t(n[2] - 1);
  b.edges = b.segments + 12 * points;
  return b;
}

double SampleSpheres::radius(const std::array<int, 3>& p) const {
  long s = -1;
  lattice_.along(p[0] - first_[0], p[1] - first_[1], p[2] - first_[2], p[2] - first_[2], &s);
  return s >= 0 ? std::abs(lattice_.value(s)) : 0.0;
}

long keep_in_fan_regions(PointMatrix& vertices, const std::vector<VertexKey>& keys,
                         const PointMatrix& before, const PointMatrix& crossing_means,
                         const std::vector<std::uint64_t>& split_cells, const GridGeometry& grid,
                         const SampleSpheres* spheres) {
  const std::array<int, 3> n = grid.whole_dims();
  const std::array<int, 3> cells{n[0] - 1, n[1] - 1, n[2] - 1};
  const VertexKeyBases bases = vertex_key_bases(n);
  const Eigen::Vector3d h = grid.spacing(), min = grid.bounds.min;
  // (A count per range, not one shared atomic: nearly every vertex moves, and two threads
  // incrementing one counter made the loop no faster on two cores than on one.)
  auto keep = [&](Eigen::Index v) {
    const std::uint64_t key = keys[std::size_t(v)][0];
    const Eigen::Vector3d was = before.row(v).transpose(), now = vertices.row(v).transpose();
    Eigen::Vector3d kept = now;
    int axis = 0;
    Eigen::Vector3d low;
    if (keys[std::size_t(v)][1] != 0) {
      // A face's vertex: on the face's plane, moved within it, a margin inside its sides.
      if (!shared_face(key, far_end_key(keys[std::size_t(v)]), cells, grid, axis, low)) {
        kept = was;
      } else {
        kept = was;
        kept[axis] = low[axis];
        for (int d = 0; d < 3; ++d)
          if (d != axis) {
            Eigen::Vector3d start = kept;
            start[d] = low[d];
            kept[d] = start[d] + place_along(start, d, h[d], was, now);
          }
      }
    } else if (key < bases.segments &&
               std::binary_search(split_cells.begin(), split_cells.end(), key / 4)) {
      kept = crossing_means.row(v).transpose();
    } else if (key < bases.segments) {
      const std::array<int, 3> c = grid_point_of(key / 4, cells);
      Eigen::Vector3d lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = min[a] + (c[std::size_t(a)] + kMargin) * h[a];
        hi[a] = min[a] + (c[std::size_t(a)] + 1 - kMargin) * h[a];
      }
      kept = slide_into_box(now, was, lo, hi);
    } else if (key < bases.edges) {
      kept = was;
    } else {
      const std::uint64_t edge = key - bases.edges;
      axis = int(edge % 3);
      const std::array<int, 3> p = edge_low_point(edge, n);
      Eigen::Vector3d start;
      for (int a = 0; a < 3; ++a) start[a] = min[a] + p[std::size_t(a)] * h[a];
      double from = 0, to = 0;
      if (spheres) {
        std::array<int, 3> q = p;
        from = spheres->radius(q);
        ++q[std::size_t(axis)];
        to = spheres->radius(q);
      }
      kept = start;
      kept[axis] += place_along(start, axis, h[axis], was, now, from, to);
    }
    if (kept == now) return 0L;
    vertices.row(v) = kept.transpose();
    return 1L;
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<Eigen::Index>(0, vertices.rows()), 0L,
      [&](const tbb::blocked_range<Eigen::Index>& r, long count) {
        for (Eigen::Index v = r.begin(); v < r.end(); ++v) count += keep(v);
        return count;
      },
      std::plus<long>());
}

void split_fan_faces(const KeyedTriangles& near, double limit, const ContactProjector& projector,
                     const GridGeometry& grid, const VertexTriangles& around, SubdividedMesh& sub,
                     PointMatrix& reconstructed) {
  const std::array<int, 3> n = grid.whole_dims();
  const std::array<int, 3> cells{n[0] - 1, n[1] - 1, n[2] - 1};
  const VertexKeyBases bases = vertex_key_bases(n);
  const PointMatrix normals = vertex_normals(sub.mesh, around);
  auto split = [&](int x, int y) {
    const VertexKey &kx = sub.keys[std::size_t(x)], &ky = sub.keys[std::size_t(y)];
    if (kx[1] != 0 || ky[1] != 0 || kx[0] >= bases.segments || ky[0] >= bases.segments)
      return false;  // only between two cells' vertices: the edge crosses their face
    if (!chord_sags(sub, normals, x, y, limit)) return false;
    // Only a chord that crosses that face: the projection can take a vertex out of its cell, and
    // a new vertex kept on the face far from its chord lay 0.77 h off armadillo at 512^3.
    int axis = 0;
    Eigen::Vector3d low, at;
    if (!chord_crossing(sub, x, y, kx[0], ky[0], cells, grid, axis, low, at)) return false;
    const Eigen::Vector3d h = grid.spacing();
    for (int d = 0; d < 3; ++d)
      if (d != axis &&
          (at[d] < low[d] - kFaceReach * h[d] || at[d] > low[d] + (1 + kFaceReach) * h[d]))
        return false;
    return true;
  };
  SplitMesh split_mesh = split_curved_edges(near, sub, 0, split);
  const Eigen::Index count = split_mesh.sub.mesh.vertices.rows();
  PointMatrix start(count, 3), placed(count, 3);
  std::vector<char> stay(std::size_t(count), 0);
  tbb::parallel_for(Eigen::Index(0), count, [&](Eigen::Index v) {
    const auto [x, y] = split_mesh.source[std::size_t(v)];
    stay[std::size_t(v)] = x == y;
    if (x == y) {
      start.row(v) = reconstructed.row(x);
      placed.row(v) = sub.mesh.vertices.row(x);
      return;
    }
    // Where the chord crosses the face between the two cells (split's test found that it does).
    const VertexKey& key = split_mesh.sub.keys[std::size_t(v)];
    int axis = 0;
    Eigen::Vector3d low, at;
    if (!chord_crossing(sub, x, y, key[0], far_end_key(key), cells, grid, axis, low, at))
      at = 0.5 * (sub.mesh.vertices.row(x) + sub.mesh.vertices.row(y)).transpose();
    start.row(v) = placed.row(v) = at.transpose();
  });
  split_mesh.sub.mesh.vertices = placed;
  sub = std::move(split_mesh.sub);
  reconstructed = start;
  projector.project(sub.mesh, &stay);
}

}  // namespace sdfcontour::detail
