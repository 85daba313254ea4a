#include "band/near_surface.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "input/parallel_select.h"
#include "input/value_scans.h"
#include "input/windowed_passes.h"

namespace sdfcontour::detail {

namespace {

// The gradient norm at sample p, next to a sign change: central differences with steps h and 2h,
// extrapolated (Richardson), so that the curvature's O(h^2) bias cancels and an exact distance
// measures 1 to O(h^4). Left out where its stencil touches a truncated value.
template <class T>
void add_crossing_norm(const T* f, std::size_t p, const std::size_t stride[3],
                       const Eigen::Vector3d& h, const Truncation& truncation,
                       NearSurfaceValues& slab) {
  if (truncation.detected())
    for (int a = 0; a < 3; ++a)
      for (long o : {-2L, -1L, 1L, 2L})
        if (truncation.truncated(double(f[p + o * long(stride[a])]))) return;
  // (hypot: squares of values as small as 1e-200 would underflow to 0.)
  double d1s[3], d2s[3], bend = 0;
  for (int a = 0; a < 3; ++a) {
    const double minus1 = double(f[p - stride[a]]), plus1 = double(f[p + stride[a]]);
    const double minus2 = double(f[p - 2 * stride[a]]), plus2 = double(f[p + 2 * stride[a]]);
    d1s[a] = (plus1 - minus1) / (2 * h[a]);
    d2s[a] = (plus2 - minus2) / (4 * h[a]);
    const double centre = 2 * double(f[p]);
    bend = std::max({bend, std::abs(plus1 - centre + minus1) / h[a],
                     std::abs(plus2 - centre + minus2) / (4 * h[a])});
  }
  const double norm =
      (4 * std::hypot(d1s[0], d1s[1], d1s[2]) - std::hypot(d2s[0], d2s[1], d2s[2])) / 3;
  slab.all.push_back(norm);
  if (bend < kSmoothCurvature) slab.smooth.push_back(norm);
  if (bend < kSmoothCurvature * std::abs(norm)) slab.kinkless.push_back(norm);
}

// |fourth differences| (1, -4, 6, -4, 1) at sample p along each axis whose stencil touches no
// truncated value: ~h^4 times the fourth derivative on a smooth field, whose second differences
// (~h^2 curvature) would read as noise on a coarse grid; sqrt(70) sigma on white noise.
template <class T>
void add_fourth_differences(const T* f, std::size_t p, const std::size_t stride[3],
                            const Truncation& truncation, std::vector<double>& d4) {
  constexpr double kWeights[5] = {1, -4, 6, -4, 1};
  const bool truncated_anywhere = truncation.detected();
  for (int a = 0; a < 3; ++a) {
    double sum = 0;
    bool clamped = false;
    for (int o = -2; o <= 2; ++o) {
      const double v = double(f[long(p) + o * long(stride[a])]);
      clamped |= truncated_anywhere && truncation.truncated(v);
      sum += kWeights[o + 2] * v;
    }
    if (!clamped) d4.push_back(std::abs(sum));
  }
}

// f(k) for each k in [from, to) where mask[k] is set, in ascending order; eight unset entries are
// passed over at once (few samples lie near the surface: stepping through every entry was most
// of measuring a 512^3 grid).
template <class F>
void for_each_marked(const unsigned char* mask, int from, int to, const F& f) {
  int k = from;
  for (; k + 8 <= to; k += 8) {
    std::uint64_t word;
    std::memcpy(&word, mask + k, sizeof word);
    if (word == 0) continue;
    for (int e = k; e < k + 8; ++e)
      if (mask[e]) f(e);
  }
  for (; k < to; ++k)
    if (mask[k]) f(k);
}

}  // namespace

std::vector<NearSurfaceValues> near_surface_values(const GridView& grid,
                                                   const Truncation& truncation,
                                                   const NearSurfaceRequest& request) {
  const std::array<int, 3>& from = request.from;
  const std::array<int, 3>& to = request.to;
  if (from[0] >= to[0] || from[1] >= to[1] || from[2] >= to[2]) return {};
  const Eigen::Vector3d h = grid.spacing();
  const std::size_t stride[3] = {std::size_t(grid.dims[1]) * std::size_t(grid.dims[2]),
                                 std::size_t(grid.dims[2]), 1};
  std::vector<NearSurfaceValues> per_slab(std::size_t(to[0] - from[0]));
  grid.visit([&](const auto* f) {
    windowed_slabs(grid, f, from[0], to[0], 2, [&](int i) {
      // Row masks first: few samples lie near the surface.
      thread_local std::vector<unsigned char> crossing, near;
      crossing.resize(std::size_t(grid.dims[2]));
      near.resize(std::size_t(grid.dims[2]));
      const std::ptrdiff_t beside[4] = {-std::ptrdiff_t(stride[0]), std::ptrdiff_t(stride[0]),
                                        -std::ptrdiff_t(stride[1]), std::ptrdiff_t(stride[1])};
      NearSurfaceValues& slab = per_slab[std::size_t(i - from[0])];
      for (int j = from[1]; j < to[1]; ++j) {
        const auto* row = f + grid.index(i, j, 0);
        if (request.norms) crossing_row(row, beside, from[2], to[2], crossing.data());
        if (request.noise) near_row(row, request.near, from[2], to[2], near.data());
        if (request.norms)
          for_each_marked(crossing.data(), from[2], to[2], [&](int k) {
            add_crossing_norm(f, grid.index(i, j, k), stride, h, truncation, slab);
          });
        if (request.noise)
          for_each_marked(near.data(), from[2], to[2], [&](int k) {
            add_fourth_differences(f, grid.index(i, j, k), stride, truncation, slab.d4);
          });
      }
    });
  });
  return per_slab;
}

double noise_of(const std::vector<NearSurfaceValues>& slabs) {
  // (The median from the slabs as they are: a copy of them, zeroed first, and a serial selection
  // over it were a tenth of a second on one thread at 512^3.)
  std::vector<ValueRun> runs;
  std::size_t count = 0;
  for (const NearSurfaceValues& slab : slabs) {
    runs.push_back({slab.d4.data(), slab.d4.size()});
    count += slab.d4.size();
  }
  if (count < 16) return NAN;
  return 1.4826 * kth_smallest(runs, count / 2) / std::sqrt(70.0);
}

std::vector<NearSurfaceValues> whole_grid_near_surface(const GridView& grid,
                                                       const Truncation& truncation, bool norms,
                                                       bool noise) {
  NearSurfaceRequest request;
  request.norms = norms;
  request.noise = noise;
  request.near = 3 * grid.spacing().maxCoeff();
  for (int a = 0; a < 3; ++a) {
    request.from[std::size_t(a)] = 2;
    request.to[std::size_t(a)] = grid.dims[std::size_t(a)] - 2;
  }
  return near_surface_values(grid, truncation, request);
}

}  // namespace sdfcontour::detail
