#include "sdfcontour/input/sparse_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "sdfcontour/extraction/brick_marching.h"

namespace sdfcontour {

std::array<int, 3> owned_dims(const SparseGrid& grid, const GridView& block) {
  std::array<int, 3> own;
  for (int a = 0; a < 3; ++a)
    own[a] = block.first[a] + block.dims[a] == grid.dims[a] ? block.dims[a] : block.dims[a] - 1;
  return own;
}

int bricks_along(int n, int brick) {
  return (n - 1 + brick - 1) / brick;
}

int SparseGrid::brick_index(int i, int j, int k) const {
  const int a = std::min(i / brick, bricks[0] - 1), b = std::min(j / brick, bricks[1] - 1),
            c = std::min(k / brick, bricks[2] - 1);
  return (a * bricks[1] + b) * bricks[2] + c;
}

double SparseGrid::value(int i, int j, int k) const {
  const int b = brick_index(i, j, k);
  const int stored = block_of[std::size_t(b)];
  if (stored < 0) return fill[std::size_t(b)];
  const GridView& block = blocks[std::size_t(stored)];
  return block.value(block.index(i - block.first[0], j - block.first[1], k - block.first[2]));
}

namespace {

std::string at_string(const std::array<int, 3>& at) {
  return "[" + std::to_string(at[0]) + ", " + std::to_string(at[1]) + ", " + std::to_string(at[2]) +
         "]";
}

// The brick's (a, b, c) from its C-order index.
std::array<int, 3> brick_coordinates(const SparseGrid& grid, int index) {
  return {index / (grid.bricks[1] * grid.bricks[2]), index / grid.bricks[2] % grid.bricks[1],
          index % grid.bricks[2]};
}

void check_block(const SparseGrid& grid, int index, const GridView& block) {
  const std::array<int, 3> b = brick_coordinates(grid, index);
  for (int a = 0; a < 3; ++a) {
    const int first = b[a] * grid.brick;
    if (block.first[a] != first ||
        block.dims[a] != std::min(grid.brick, grid.dims[a] - 1 - first) + 1)
      throw Error("brick " + at_string(b) + " of the sparse grid has the wrong place or size");
    if (block.whole != grid.dims) throw Error("a block of the sparse grid names another grid");
  }
  if (!block.data) throw Error("brick " + at_string(b) + " of the sparse grid has no values");
  if (const auto at = first_non_finite(block))
    throw Error("grid values contain a NaN, infinite or too large (over 1e100) value (at " +
                at_string(*at) + ")");
}

}  // namespace

void validate_sparse_grid(const SparseGrid& grid) {
  validate_grid_geometry(grid);
  if (grid.brick < 1) throw Error("the sparse grid's bricks must be at least one cell wide");
  std::size_t count = 1;
  for (int a = 0; a < 3; ++a) {
    if (grid.bricks[a] != bricks_along(grid.dims[a], grid.brick))
      throw Error("the sparse grid's brick counts do not match its dims");
    count *= std::size_t(grid.bricks[a]);
  }
  if (grid.fill.size() != count || grid.block_of.size() != count)
    throw Error("the sparse grid needs one fill value and one block slot per brick");
  std::vector<char> seen(grid.blocks.size(), 0);
  for (std::size_t b = 0; b < count; ++b) {
    const int stored = grid.block_of[b];
    if (stored < 0) {
      if (!(std::abs(grid.fill[b]) <= 1e100))
        throw Error("the sparse grid's fill value of brick " +
                    at_string(brick_coordinates(grid, int(b))) + " is not finite");
      continue;
    }
    if (std::size_t(stored) >= grid.blocks.size() || seen[std::size_t(stored)]++)
      throw Error("the sparse grid's block slots do not name each block once");
    check_block(grid, int(b), grid.blocks[std::size_t(stored)]);
  }
  if (std::find(seen.begin(), seen.end(), 0) != seen.end())
    throw Error("the sparse grid holds a block that no brick names");
}

void require_sign_change(const SparseGrid& grid) {
  bool inside = false, outside = false;
  for (std::size_t b = 0; b < grid.fill.size(); ++b)
    if (grid.block_of[b] < 0) (grid.fill[b] < 0 ? inside : outside) = true;
  for (const GridView& block : grid.blocks) {
    if (inside && outside) break;
    block.visit([&](const auto* f) {
      for (std::size_t p = 0; p < block.size() && !(inside && outside); ++p)
        (f[p] < 0 ? inside : outside) = true;
    });
  }
  if (!(inside && outside))
    throw Error(std::string("no surface: every value is ") +
                (inside ? "negative" : "non-negative") + ", so the field has no sign change");
}

long sign_change_edges(const SparseGrid& grid) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, grid.blocks.size(), 1), 0L,
      [&](const tbb::blocked_range<std::size_t>& r, long count) {
        for (std::size_t s = r.begin(); s < r.end(); ++s) {
          const GridView& block = grid.blocks[s];
          const std::array<int, 3>& d = block.dims;
          const std::array<int, 3> own = owned_dims(grid, block);
          block.visit([&](const auto* f) {
            for (int i = 0; i < own[0]; ++i)
              for (int j = 0; j < own[1]; ++j)
                for (int k = 0; k < own[2]; ++k) {
                  const std::size_t p = block.index(i, j, k);
                  const bool in = f[p] < 0;
                  if (i + 1 < d[0]) count += (f[block.index(i + 1, j, k)] < 0) != in;
                  if (j + 1 < d[1]) count += (f[block.index(i, j + 1, k)] < 0) != in;
                  if (k + 1 < d[2]) count += (f[p + 1] < 0) != in;
                }
          });
        }
        return count;
      },
      std::plus<long>());
}

bool sides_inside(const SparseGrid& grid) {
  const std::array<int, 3>& n = grid.dims;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int side : {0, n[a] - 1})
      for (int u = 0; u < n[b]; ++u)
        for (int v = 0; v < n[c]; ++v) {
          std::array<int, 3> at;
          at[a] = side;
          at[b] = u;
          at[c] = v;
          if (grid.value(at[0], at[1], at[2]) < 0) return true;
        }
  }
  return false;
}

Mesh marching_cubes(const SparseGrid& grid) {
  // Pieces in the bricks' C order, so that the mesh does not depend on the blocks' order.
  std::vector<int> order;
  for (int b : grid.block_of)
    if (b >= 0) order.push_back(b);
  std::vector<MeshPiece> pieces(order.size());
  tbb::parallel_for(std::size_t(0), order.size(), [&](std::size_t s) {
    const GridView& block = grid.blocks[std::size_t(order[s])];
    pieces[s] = marching_cubes_brick(block, grid, block.first);
  });
  return join_mesh_pieces(pieces);
}

}  // namespace sdfcontour
