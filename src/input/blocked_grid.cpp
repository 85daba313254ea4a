#include "sdfcontour/input/blocked_grid.h"

#include <string>

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

}  // namespace sdfcontour
