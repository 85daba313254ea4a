#include "sdfcontour/self_intersections.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace sdfcontour {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

// Triangles bucketed by the cube of side `cell` holding their bounding box's centre, sorted by
// cube (x fastest). `cell` is at least every triangle's extent, so a triangle whose box meets a
// given box has its centre within `cell` of it.
class TriangleCubes {
 public:
  explicit TriangleCubes(const std::vector<Eigen::AlignedBox3d>& boxes) {
    Eigen::AlignedBox3d all;
    cell_ = 0;
    for (const auto& b : boxes) {
      all.extend(b);
      cell_ = std::max(cell_, (b.max() - b.min()).maxCoeff());
    }
    origin_ = all.min();
    const Eigen::Vector3d extent = all.max() - all.min();
    cell_ = std::max(cell_, 1e-12 * std::max(extent.maxCoeff(), 1e-300));
    // Keys must fit in 63 bits whatever the spread: coarser cubes only cost more tests.
    while (((extent / cell_).array() + 1).prod() > 1e17) cell_ *= 2;
    for (int a = 0; a < 3; ++a) size_[a] = long(extent[a] / cell_) + 1;
    keyed_.resize(boxes.size());
    tbb::parallel_for(std::size_t(0), boxes.size(), [&](std::size_t t) {
      const auto c = cube_of(boxes[t].center());
      keyed_[t] = {key(c[0], c[1], c[2]), int(t)};
    });
    tbb::parallel_sort(keyed_.begin(), keyed_.end());
  }

  // Calls f(triangle) for every triangle whose box may meet `box`.
  template <class F>
  void for_each_near(const Eigen::AlignedBox3d& box, F&& f) const {
    const auto lo = cube_of(box.min().array() - cell_), hi = cube_of(box.max().array() + cell_);
    for (long k = lo[2]; k <= hi[2]; ++k)
      for (long j = lo[1]; j <= hi[1]; ++j) {
        auto it = std::lower_bound(keyed_.begin(), keyed_.end(),
                                   std::pair<long, int>{key(lo[0], j, k), -1});
        const long end = key(hi[0], j, k);
        for (; it != keyed_.end() && it->first <= end; ++it) f(it->second);
      }
  }

 private:
  std::array<long, 3> cube_of(const Eigen::Vector3d& p) const {
    std::array<long, 3> c;
    for (int a = 0; a < 3; ++a)
      c[std::size_t(a)] =
          std::clamp(long(std::floor((p[a] - origin_[a]) / cell_)), 0L, size_[a] - 1);
    return c;
  }
  long key(long i, long j, long k) const { return (k * size_[1] + j) * size_[0] + i; }

  double cell_ = 1;
  Eigen::Vector3d origin_;
  long size_[3] = {1, 1, 1};
  std::vector<std::pair<long, int>> keyed_;
};

// Whether triangles s and t (not sharing an edge) meet other than in a shared vertex.
bool cross(const Mesh& mesh, int s, int t) {
  auto at = [&](int v) {
    return Point(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2));
  };
  const auto S = mesh.triangles.row(s), T = mesh.triangles.row(t);
  int shared_s = -1, shared_t = -1, shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (S[i] == T[j]) shared_s = i, shared_t = j, ++shared;
  if (shared >= 2) return false;
  const K::Triangle_3 a(at(S[0]), at(S[1]), at(S[2])), b(at(T[0]), at(T[1]), at(T[2]));
  if (shared == 0) return CGAL::do_intersect(a, b);
  // One shared vertex: they cross elsewhere iff an edge opposite it cuts the other triangle.
  const K::Segment_3 opposite_s(at(S[(shared_s + 1) % 3]), at(S[(shared_s + 2) % 3])),
      opposite_t(at(T[(shared_t + 1) % 3]), at(T[(shared_t + 2) % 3]));
  return CGAL::do_intersect(opposite_s, b) || CGAL::do_intersect(opposite_t, a);
}

bool degenerate(const Mesh& mesh, int t) {
  const auto T = mesh.triangles.row(t);
  auto at = [&](int v) {
    return Point(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2));
  };
  return CGAL::collinear(at(T[0]), at(T[1]), at(T[2]));
}

}  // namespace

std::vector<std::pair<int, int>> self_intersecting_triangles(const Mesh& mesh,
                                                             const std::vector<char>* watch) {
  const Eigen::Index m = mesh.triangles.rows();
  if (watch && watch->size() != std::size_t(m))
    throw Error("self-intersections: " + std::to_string(watch->size()) + " flags for " +
                std::to_string(m) + " triangles");
  if (m < 2) return {};
  std::vector<Eigen::AlignedBox3d> boxes(static_cast<std::size_t>(m));
  std::vector<char> flat(static_cast<std::size_t>(m), 0);
  tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index t) {
    auto& box = boxes[std::size_t(t)];
    for (int c = 0; c < 3; ++c) box.extend(mesh.vertices.row(mesh.triangles(t, c)).transpose());
    flat[std::size_t(t)] = degenerate(mesh, int(t));
  });
  const TriangleCubes cubes(boxes);
  auto watched = [&](int t) { return !watch || (*watch)[std::size_t(t)]; };
  tbb::enumerable_thread_specific<std::vector<std::pair<int, int>>> found;
  tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index ti) {
    const int t = int(ti);
    if (!watched(t) || flat[std::size_t(t)]) return;
    cubes.for_each_near(boxes[std::size_t(t)], [&](int u) {
      // Each pair once: from its lower triangle when both are watched.
      if (u == t || (watched(u) && u < t) || flat[std::size_t(u)]) return;
      if (!boxes[std::size_t(t)].intersects(boxes[std::size_t(u)])) return;
      if (cross(mesh, t, u)) found.local().emplace_back(std::min(t, u), std::max(t, u));
    });
  });
  std::vector<std::pair<int, int>> pairs;
  for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

UntangleStats revert_self_intersections(Mesh& mesh, const PointMatrix& before) {
  if (before.rows() != mesh.vertices.rows())
    throw Error("self-intersections: " + std::to_string(before.rows()) + " earlier positions for " +
                std::to_string(mesh.vertices.rows()) + " vertices");
  UntangleStats stats;
  const Eigen::Index n = mesh.vertices.rows(), m = mesh.triangles.rows();
  auto moved = [&](int v) { return mesh.vertices.row(v) != before.row(v); };
  // First the triangles around any moved vertex, then those around the vertices moved back.
  std::vector<char> watch(std::size_t(m), 0);
  for (Eigen::Index t = 0; t < m; ++t)
    for (int c = 0; c < 3; ++c) watch[std::size_t(t)] |= moved(mesh.triangles(t, c));
  for (;;) {
    const auto pairs = self_intersecting_triangles(mesh, &watch);
    if (stats.rounds++ == 0) stats.intersections_found = long(pairs.size());
    std::vector<char> back(std::size_t(n), 0);
    bool any = false;
    for (const auto& [s, t] : pairs)
      for (int tri : {s, t})
        for (int c = 0; c < 3; ++c) {
          const int v = mesh.triangles(tri, c);
          if (moved(v)) back[std::size_t(v)] = 1, any = true;
        }
    if (!any) {
      stats.intersections_left = long(pairs.size());
      return stats;
    }
    for (Eigen::Index v = 0; v < n; ++v)
      if (back[std::size_t(v)]) mesh.vertices.row(v) = before.row(v), ++stats.vertices_reverted;
    for (Eigen::Index t = 0; t < m; ++t) {
      bool around = false;
      for (int c = 0; c < 3; ++c) around |= back[std::size_t(mesh.triangles(t, c))] != 0;
      watch[std::size_t(t)] = around;
    }
  }
}

}  // namespace sdfcontour
