// Grid edges that a part thinner than a spacing may cross unseen (subspacing_gaps.h).
#include "sdfcontour/band/subspacing_gaps.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "input/windowed_passes.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

SubspacingGaps count_subspacing_gaps(const GridView& grid, std::array<int, 3> own_first,
                                     std::array<int, 3> own_end, double value_scale) {
  const std::array<int, 3> whole = grid.whole_dims();
  std::array<int, 3> from{}, to{};  // block indices of the owned lower samples
  for (int a = 0; a < 3; ++a) {
    const int lo = std::max(own_first[a], 0), hi = std::min(own_end[a], whole[a]);
    from[a] = lo - grid.first[a];
    to[a] = hi - grid.first[a];
    if (lo >= hi) return {};
    const int last = grid.first[a] + grid.dims[a] - 1;  // the block's last whole-grid index
    if ((lo > 0 && grid.first[a] > lo - 1) || last < std::min(hi + 1, whole[a] - 1))
      throw Error("the block must hold one sample before and two after the edges it counts");
  }
  const Eigen::Vector3d h = grid.spacing();
  const std::size_t stride[3] = {std::size_t(grid.dims[1]) * std::size_t(grid.dims[2]),
                                 std::size_t(grid.dims[2]), 1};
  std::vector<SubspacingGaps> per_slab(std::size_t(to[0] - from[0]));
  grid.visit([&](const auto* f) {
    detail::windowed_slabs(grid, f, from[0], to[0], 1, [&](int i) {
      SubspacingGaps& counts = per_slab[std::size_t(i - from[0])];
      for (int j = from[1]; j < to[1]; ++j)
        for (int k = from[2]; k < to[2]; ++k) {
          const std::array<int, 3> at{grid.first[0] + i, grid.first[1] + j, grid.first[2] + k};
          const std::size_t p = grid.index(i, j, k);
          const double v1 = double(f[p]) * value_scale;
          for (int a = 0; a < 3; ++a) {
            if (at[a] + 1 >= whole[a]) continue;
            const std::size_t s = stride[a];
            const double v2 = double(f[p + s]) * value_scale;
            const bool inside = v1 < 0;
            if (inside != (v2 < 0)) {
              ++counts.crossings;
              continue;
            }
            if (at[a] == 0 || at[a] + 2 >= whole[a] || std::abs(v1) + std::abs(v2) >= h[a])
              continue;
            const double side = inside ? -1 : 1;
            const double before = double(f[p - s]) * value_scale,
                         after = double(f[p + 2 * s]) * value_scale;
            counts.gaps += side * (before - v1) > h[a] / 2 && side * (after - v2) > h[a] / 2;
          }
        }
    });
  });
  SubspacingGaps total;
  for (const SubspacingGaps& c : per_slab) {
    total.gaps += c.gaps;
    total.crossings += c.crossings;
  }
  return total;
}

SubspacingGaps count_subspacing_gaps(const GridView& grid, double value_scale) {
  return count_subspacing_gaps(grid, {0, 0, 0}, grid.whole_dims(), value_scale);
}

SubspacingGaps count_subspacing_gaps(const BlockedGrid& grid, double value_scale, int brick) {
  if (brick < 1) throw Error("the bricks must be at least one sample wide");
  SubspacingGaps sum;
  std::vector<float> values;
  const std::vector<long> visit = bricks_to_visit(grid, grid.dims, brick, 2);
  for_each_listed_brick(grid.dims, brick, visit,
                 [&](long, const std::array<int, 3>& own_first, const std::array<int, 3>& own_end) {
                   std::array<int, 3> lo, hi;  // the samples its edges need
                   for (std::size_t a = 0; a < 3; ++a) {
                     lo[a] = std::max(own_first[a] - 1, 0);
                     hi[a] = std::min(own_end[a] + 2, grid.dims[a]);
                   }
                   if (grid.may_hold_surface && !grid.may_hold_surface(lo, hi)) return;
                   const SubspacingGaps piece = count_subspacing_gaps(
                       read_block(grid, lo, hi, values), own_first, own_end, value_scale);
                   sum.gaps += piece.gaps;
                   sum.crossings += piece.crossings;
                 });
  return sum;
}

}  // namespace sdfcontour
