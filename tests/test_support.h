// Shared helpers for the tests.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sdfcontour/input/blocked_grid.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/input/signed_distance.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/metrics/mesh_properties.h"

namespace sdfcontour::test {

/// Removes the temporary directories the tests made when the test program ends.
struct TempDirs {
  std::vector<std::filesystem::path> made;
  ~TempDirs() {
    std::error_code ec;
    for (const auto& d : made) std::filesystem::remove_all(d, ec);
  }
};

/// A fresh temporary directory for one test, removed when the test program ends.
inline std::filesystem::path temp_dir(const std::string& name) {
  static TempDirs dirs;
  auto dir = std::filesystem::temp_directory_path() /
             ("sdfcontour_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  dirs.made.push_back(dir);
  return dir;
}

/// Skips the calling test, with the reason, unless `path` exists (an optional peer or data).
#define SDFCONTOUR_REQUIRE_PATH(path, what)                                                   \
  do {                                                                                        \
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "needs " << what << " at " << (path); \
  } while (0)

/// Skips the calling test unless the shared test meshes (../shared/data/meshes) are there: a
/// plain clone has none.
#define SDFCONTOUR_REQUIRE_SHARED_MESHES() \
  SDFCONTOUR_REQUIRE_PATH(SDFCONTOUR_SHARED_DIR "/data/meshes", "the shared test meshes")

/// Skips the calling test unless Debian's python3 can import `module`.
#define SDFCONTOUR_REQUIRE_PYTHON_MODULE(module)                                                   \
  do {                                                                                             \
    if (std::system("/usr/bin/python3 -c 'import " module "' 2>/dev/null") != 0)                   \
      GTEST_SKIP() << "needs Debian's python3 with " module " (apt-get install python3-" << module \
                   << ")";                                                                         \
  } while (0)

/// The exact SDF grid (n^3 over [-1, 1]^3) of the shared mesh `name` (in
/// ../shared/data/meshes), scaled as `sdfcontour sample` does (longest side 1.8, centred).
inline Grid shared_mesh_grid(const std::string& name, int n) {
  const MeshSdf sdf(
      normalize_mesh(read_mesh(SDFCONTOUR_SHARED_DIR "/data/meshes/" + name + ".obj"), 0.9));
  return sample_grid(sdf, n, Bounds{});
}

/// n points uniformly random in [-1, 1]^3.
inline PointMatrix random_points(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PointMatrix p(n, 3);
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) p(i, a) = u(rng);
  return p;
}

/// A 4^3 grid of positive values whose middle cube's corner c is inside (negative) where bit c
/// of `mask` is set: one of the 254 mixed sign patterns, padded so that its surface must close.
inline Grid single_cube_grid(int mask) {
  Grid g;
  g.dims = {4, 4, 4};
  g.values = Eigen::VectorXd::Constant(64, 1.0);
  for (int c = 0; c < 8; ++c)
    g.values[Eigen::Index(g.index(1 + (c & 1), 1 + (c >> 1 & 1), 1 + (c >> 2 & 1)))] =
        (mask >> c & 1) ? -0.3 - 0.1 * c : 0.2 + 0.05 * c;
  return g;
}

/// The n^3 grid over [-1, 1]^3 as scattered points.
inline PointMatrix grid_points(int n) {
  Grid g;
  g.dims = {n, n, n};
  g.values = Eigen::VectorXd::Zero(Eigen::Index(g.size()));
  return g.to_samples().points;
}

/// The mesh with vertices sorted by position and triangles named by sorted ranks, each rotated to
/// start at its smallest rank, sorted: equal for two meshes iff they have the same vertex
/// positions (bit for bit) and the same triangles, whatever the order.
using Canonical = std::pair<std::vector<std::array<double, 3>>, std::vector<std::array<int, 3>>>;
inline Canonical canonical(const Mesh& m) {
  const int n = int(m.vertices.rows());
  std::vector<int> order(static_cast<std::size_t>(n)), rank(static_cast<std::size_t>(n));
  for (int v = 0; v < n; ++v) order[std::size_t(v)] = v;
  auto at = [&](int v) {
    return std::array<double, 3>{m.vertices(v, 0), m.vertices(v, 1), m.vertices(v, 2)};
  };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return at(a) < at(b); });
  Canonical c;
  for (int r = 0; r < n; ++r) {
    rank[std::size_t(order[std::size_t(r)])] = r;
    c.first.push_back(at(order[std::size_t(r)]));
  }
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t) {
    std::array<int, 3> tri{rank[std::size_t(m.triangles(t, 0))],
                           rank[std::size_t(m.triangles(t, 1))],
                           rank[std::size_t(m.triangles(t, 2))]};
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    c.second.push_back(tri);
  }
  std::sort(c.second.begin(), c.second.end());
  return c;
}

/// Mean |shape's distance| at the triangles' centroids of `m`: a chord's worst point, not its
/// ends, so where a mesh of a smooth surface sags.
inline double mean_centroid_distance(const Mesh& m, const AnalyticShape& shape) {
  double sum = 0;
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) c += m.vertices.row(m.triangles(t, k)).transpose() / 3;
    sum += std::abs(shape.distance(c));
  }
  return sum / double(m.triangles.rows());
}

/// Closed (every edge has two triangles), consistently oriented, outward (positive volume).
inline void expect_closed_and_outward(const Mesh& m) {
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(t.closed) << t.boundary_edges << " boundary, " << t.nonmanifold_edges
                        << " non-manifold edges";
  EXPECT_TRUE(t.consistently_oriented);
  EXPECT_GT(signed_volume(m), 0) << "not outward oriented";
}

// Every vertex's triangles form one fan (a closed disc), as mesh_topology's edge test does not
// check.
inline bool vertices_manifold(const Mesh& m) {
  std::vector<std::vector<std::pair<int, int>>> link(std::size_t(m.vertices.rows()));
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      link[std::size_t(m.triangles(t, k))].push_back(
          {m.triangles(t, (k + 1) % 3), m.triangles(t, (k + 2) % 3)});
  for (const auto& edges : link) {
    if (edges.empty()) continue;
    std::map<int, int> next;
    for (const auto& [a, b] : edges)
      if (!next.emplace(a, b).second) return false;
    int at = edges[0].first;
    std::size_t steps = 0;
    do {
      const auto it = next.find(at);
      if (it == next.end()) return false;
      at = it->second;
      ++steps;
    } while (at != edges[0].first && steps <= edges.size());
    if (steps != edges.size()) return false;
  }
  return true;
}

/// Corner c of the origin-centred box with half extents `half`: bit k of c set for +half[k].
inline Eigen::Vector3d box_corner(const Eigen::Vector3d& half, int c) {
  return {(c & 1 ? 1 : -1) * half[0], (c & 2 ? 1 : -1) * half[1], (c & 4 ? 1 : -1) * half[2]};
}

/// The distance from p to the nearest row of `rows` (n x 3; infinite for none).
inline double nearest_row_distance(const PointMatrix& rows, const Eigen::Vector3d& p) {
  double nearest = INFINITY;
  for (Eigen::Index r = 0; r < rows.rows(); ++r)
    nearest = std::min(nearest, (rows.row(r).transpose() - p).norm());
  return nearest;
}

/// The float32 grid `values` (viewed by `view`) as a grid read a block at a time: each read
/// counted in `reads`, and a block whose every |value| is at least `band` said to hold no surface
/// (counted in `unread`), as a level set's blocks outside its leaves.
inline BlockedGrid blocked_grid_of(const GridView& view, const std::vector<float>& values,
                                   float band, int& reads, int& unread) {
  BlockedGrid blocked;
  static_cast<GridGeometry&>(blocked) = static_cast<const GridGeometry&>(view);
  auto each = [&view](const std::array<int, 3>& lo, const std::array<int, 3>& hi, auto&& f) {
    for (int i = lo[0]; i < hi[0]; ++i)
      for (int j = lo[1]; j < hi[1]; ++j)
        for (int k = lo[2]; k < hi[2]; ++k) f(view.index(i, j, k));
  };
  blocked.read = [&, each](const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    ++reads;
    std::vector<float> block;
    each(lo, hi, [&](std::size_t at) { block.push_back(values[at]); });
    return block;
  };
  blocked.may_hold_surface = [&, each, band](const std::array<int, 3>& lo,
                                             const std::array<int, 3>& hi) {
    bool near = false;
    each(lo, hi, [&](std::size_t at) { near = near || std::abs(values[at]) < band; });
    unread += !near;
    return near;
  };
  return blocked;
}

}  // namespace sdfcontour::test
