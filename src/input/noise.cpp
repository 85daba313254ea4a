#include "sdfcontour/input/noise.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "input/parallel_select.h"
#include "input/value_scans.h"
#include "input/windowed_passes.h"

namespace sdfcontour {

double noise_level(const GridView& grid, const Truncation& truncation) {
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  if (nx < 5 || ny < 5 || nz < 5) return NAN;
  const double near = 3 * grid.spacing().maxCoeff();
  const long stride[3] = {long(ny) * long(nz), long(nz), 1};
  // Fourth differences (1, -4, 6, -4, 1): ~h^4 times the fourth derivative on a smooth field,
  // whose second differences (~h^2 curvature) would read as noise on a coarse grid; sqrt(70)
  // sigma on white noise.
  constexpr double kWeights[5] = {1, -4, 6, -4, 1};
  struct Slab {
    std::vector<double> d4;
  };
  std::vector<Slab> per_slab(static_cast<std::size_t>(nx));
  const bool truncated_anywhere = truncation.detected();
  grid.visit([&](const auto* f) {
    detail::windowed_slabs(grid, f, 2, nx - 2, 2, [&](int i) {
      // A row's mask first: few samples lie near the surface.
      thread_local std::vector<unsigned char> row_mask;
      row_mask.resize(std::size_t(nz));
      for (int j = 2; j + 2 < ny; ++j) {
        detail::near_row(f + grid.index(i, j, 0), near, 2, nz - 2, row_mask.data());
        for (int k = 2; k + 2 < nz; ++k) {
          if (!row_mask[std::size_t(k)]) continue;
          const long p = long(grid.index(i, j, k));
          for (int a = 0; a < 3; ++a) {
            double sum = 0;
            bool clamped = false;
            for (int o = -2; o <= 2; ++o) {
              const double v = double(f[p + o * stride[a]]);
              clamped |= truncated_anywhere && truncation.truncated(v);
              sum += kWeights[o + 2] * v;
            }
            if (!clamped) per_slab[std::size_t(i)].d4.push_back(std::abs(sum));
          }
        }
      }
    });
  });
  // (The median from the slabs as they are: a copy of them, zeroed first, and a serial selection
  // over it were a tenth of a second on one thread at 512^3.)
  std::vector<detail::ValueRun> runs;
  std::size_t count = 0;
  for (const Slab& slab : per_slab) {
    runs.push_back({slab.d4.data(), slab.d4.size()});
    count += slab.d4.size();
  }
  if (count < 16) return NAN;
  return 1.4826 * detail::kth_smallest(runs, count / 2) / std::sqrt(70.0);
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
