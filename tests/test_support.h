// Shared helpers for the tests.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "sdfcontour/io.h"
#include "sdfcontour/mesh_sdf.h"
#include "sdfcontour/mesh_transform.h"
#include "sdfcontour/samples.h"
#include "sdfcontour/signed_distance.h"

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

}  // namespace sdfcontour::test
