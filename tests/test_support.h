// Shared helpers for the tests.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>

#include "sdfcontour/samples.h"

namespace sdfcontour::test {

/// A fresh temporary directory for one test.
inline std::filesystem::path temp_dir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() /
             ("sdfcontour_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
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

/// The n^3 grid over [-1, 1]^3 as scattered points.
inline PointMatrix grid_points(int n) {
  Grid g;
  g.dims = {n, n, n};
  g.values = Eigen::VectorXd::Zero(Eigen::Index(g.size()));
  return g.to_samples().points;
}

}  // namespace sdfcontour::test
