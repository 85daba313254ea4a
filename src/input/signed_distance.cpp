#include "sdfcontour/input/signed_distance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>

namespace sdfcontour {

using Eigen::Vector3d;

Grid sample_grid(const AnalyticShape& shape, int n, const Bounds& bounds) {
  Grid grid;
  grid.dims = {n, n, n};
  grid.bounds = bounds;
  grid.values.resize(Eigen::Index(grid.size()));
  tbb::parallel_for(0, n, [&](int i) {
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        grid.values[Eigen::Index(grid.index(i, j, k))] = shape.distance(grid.point(i, j, k));
  });
  return grid;
}

Grid sample_grid_truncated(const AnalyticShape& shape, int n, const Bounds& bounds,
                           double truncation, std::size_t* evaluations) {
  if (!(truncation > 0)) throw Error("the truncation distance must be positive");
  constexpr int kBlock = 8;
  Grid grid;
  grid.dims = {n, n, n};
  grid.bounds = bounds;
  grid.values.resize(Eigen::Index(grid.size()));
  const int blocks = (n + kBlock - 1) / kBlock;
  std::atomic<std::size_t> count{0};
  tbb::parallel_for(0, blocks * blocks, [&](int bij) {
    const int bi = bij / blocks, bj = bij % blocks;
    std::size_t evaluated = 0;
    for (int bk = 0; bk < blocks; ++bk) {
      const int lo[3] = {bi * kBlock, bj * kBlock, bk * kBlock};
      const int hi[3] = {std::min(lo[0] + kBlock, n) - 1, std::min(lo[1] + kBlock, n) - 1,
                         std::min(lo[2] + kBlock, n) - 1};
      const Vector3d a = grid.point(lo[0], lo[1], lo[2]), b = grid.point(hi[0], hi[1], hi[2]);
      const double centre = shape.distance((a + b) / 2);
      ++evaluated;
      const bool far = std::abs(centre) - (b - a).norm() / 2 >= truncation;
      for (int i = lo[0]; i <= hi[0]; ++i)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int k = lo[2]; k <= hi[2]; ++k) {
            double v = centre < 0 ? -truncation : truncation;
            if (!far) {
              v = std::clamp(shape.distance(grid.point(i, j, k)), -truncation, truncation);
              ++evaluated;
            }
            grid.values[Eigen::Index(grid.index(i, j, k))] = v;
          }
    }
    count += evaluated;
  });
  if (evaluations) *evaluations = count;
  return grid;
}

Samples sample_random(const AnalyticShape& shape, std::size_t count, const Bounds& bounds,
                      std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Samples s;
  s.points.resize(Eigen::Index(count), 3);
  s.values.resize(Eigen::Index(count));
  for (std::size_t i = 0; i < count; ++i) {
    Vector3d p;
    // 53 random bits per coordinate, mapped to [min, max): reproducible across standard libraries.
    for (int a = 0; a < 3; ++a) {
      const double u = double(rng() >> 11) * 0x1.0p-53;
      p[a] = bounds.min[a] + u * (bounds.max[a] - bounds.min[a]);
    }
    s.points.row(Eigen::Index(i)) = p;
  }
  tbb::parallel_for(Eigen::Index(0), s.points.rows(), [&](Eigen::Index i) {
    s.values[i] = shape.distance(s.points.row(i).transpose());
  });
  return s;
}

}  // namespace sdfcontour
