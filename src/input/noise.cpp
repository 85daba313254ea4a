#include "sdfcontour/input/noise.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "band/near_surface.h"

namespace sdfcontour {

double noise_level(const GridView& grid, const Truncation& truncation) {
  return detail::noise_of(detail::whole_grid_near_surface(grid, truncation, false, true));
}

namespace {

// Convolves every line along `axis` of `values` (C order, dims) with `kernel` (odd size),
// repeating the edge values.
void convolve_axis(double* values, const std::array<int, 3>& dims, int axis,
                   const std::vector<double>& kernel) {
  const int n = dims[std::size_t(axis)], half = int(kernel.size() / 2);
  const std::size_t stride = axis == 0   ? std::size_t(dims[1]) * std::size_t(dims[2])
                             : axis == 1 ? std::size_t(dims[2])
                                         : 1;
  // Lines: every (i, j, k) with the axis coordinate 0.
  const int others[2] = {axis == 0 ? 1 : 0, axis == 2 ? 1 : 2};
  const long lines = long(dims[std::size_t(others[0])]) * dims[std::size_t(others[1])];
  tbb::parallel_for(0L, lines, [&](long line) {
    int c[3] = {0, 0, 0};
    c[others[0]] = int(line / dims[std::size_t(others[1])]);
    c[others[1]] = int(line % dims[std::size_t(others[1])]);
    const std::size_t start =
        (std::size_t(c[0]) * std::size_t(dims[1]) + std::size_t(c[1])) * std::size_t(dims[2]) +
        std::size_t(c[2]);
    std::vector<double> in(static_cast<std::size_t>(n));
    for (int t = 0; t < n; ++t) in[std::size_t(t)] = values[start + std::size_t(t) * stride];
    for (int t = 0; t < n; ++t) {
      double sum = 0;
      for (int o = -half; o <= half; ++o)
        sum += kernel[std::size_t(o + half)] * in[std::size_t(std::clamp(t + o, 0, n - 1))];
      values[start + std::size_t(t) * stride] = sum;
    }
  });
}

}  // namespace

Grid gaussian_smoothed(const GridView& grid, double sigma) {
  if (!(sigma > 0) || !std::isfinite(sigma))
    throw Error("the smoothing's sigma must be a positive number of samples");
  Grid out;
  out.dims = grid.dims;
  out.bounds = grid.bounds;
  out.values.resize(Eigen::Index(grid.size()));
  for (std::size_t p = 0; p < grid.size(); ++p) out.values[Eigen::Index(p)] = grid.value(p);
  const int half = int(std::ceil(3 * sigma));
  std::vector<double> kernel(std::size_t(2 * half + 1));
  double total = 0;
  for (int o = -half; o <= half; ++o)
    total += kernel[std::size_t(o + half)] = std::exp(-0.5 * o * o / (sigma * sigma));
  for (double& w : kernel) w /= total;
  for (int axis = 0; axis < 3; ++axis) convolve_axis(out.values.data(), out.dims, axis, kernel);
  return out;
}

}  // namespace sdfcontour
