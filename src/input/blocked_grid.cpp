#include "sdfcontour/input/blocked_grid.h"

#include <string>

#include "sdfcontour/types.h"

namespace sdfcontour {

GridView read_block(const BlockedGrid& grid, const std::array<int, 3>& lo,
                    const std::array<int, 3>& hi, std::vector<float>& values) {
  GridView block;
  block.bounds = grid.bounds;
  block.first = lo;
  block.whole = grid.dims;
  for (std::size_t a = 0; a < 3; ++a) {
    if (!(0 <= lo[a] && lo[a] < hi[a] && hi[a] <= grid.dims[a]))
      throw Error("a block to read must lie inside its grid");
    block.dims[a] = hi[a] - lo[a];
  }
  values = grid.read(lo, hi);
  if (values.size() != block.size())
    throw InternalError("a grid's reader gave " + std::to_string(values.size()) +
                        " values for a block of " + std::to_string(block.size()));
  block.data = values.data();
  block.type = ScalarType::Float32;
  return block;
}

std::vector<long> bricks_meeting(const std::array<int, 3>& extent, int side,
                                 const std::vector<SampleBox>* boxes, int grow) {
  if (side < 1) throw Error("the bricks must be at least one sample wide");
  std::array<long, 3> count;
  for (std::size_t a = 0; a < 3; ++a) count[a] = (long(extent[a]) + side - 1) / side;
  std::vector<long> out;
  if (!boxes) {
    out.resize(std::size_t(count[0] * count[1] * count[2]));
    for (std::size_t b = 0; b < out.size(); ++b) out[b] = long(b);
    return out;
  }
  auto floor_div = [](long a, long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
  for (const SampleBox& box : *boxes) {
    // Brick c covers [c side - grow, (c + 1) side + grow): it meets [lo, hi) for c in [first, last].
    std::array<long, 3> first, last;
    bool empty = false;
    for (std::size_t a = 0; a < 3; ++a) {
      first[a] = std::max(0L, floor_div(long(box.lo[a]) - grow, side));
      last[a] = std::min(count[a] - 1, floor_div(long(box.hi[a]) + grow - 1, side));
      empty = empty || box.lo[a] >= box.hi[a] || first[a] > last[a];
    }
    if (empty) continue;
    for (long i = first[0]; i <= last[0]; ++i)
      for (long j = first[1]; j <= last[1]; ++j)
        for (long k = first[2]; k <= last[2]; ++k) out.push_back((i * count[1] + j) * count[2] + k);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace sdfcontour
