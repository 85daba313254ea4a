// The cells that the surface crosses (surface_cells.h), against their corners read one by one.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "reconstruction/local/surface_cells.h"

using namespace sdfcontour;

namespace {

// The keys of the cells in [lo, hi) whose eight corners have both signs (a value < 0 and one
// that is not), in ascending order.
template <class T>
std::vector<std::int64_t> crossed_cells(const GridView& g, const std::vector<T>& v,
                                        const std::array<int, 3>& lo,
                                        const std::array<int, 3>& hi) {
  std::vector<std::int64_t> keys;
  for (int i = lo[0]; i < hi[0]; ++i)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int k = lo[2]; k < hi[2]; ++k) {
        int inside = 0;
        for (int c = 0; c < 8; ++c)
          inside += v[g.index(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))] < 0;
        if (inside > 0 && inside < 8)
          keys.push_back((std::int64_t(i) * (g.dims[1] - 1) + j) * (g.dims[2] - 1) + k);
      }
  return keys;
}

template <class T>
void check_random_grids(ScalarType type) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> dim(2, 12);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 400; ++trial) {
    GridView g;
    g.dims = {dim(rng), dim(rng), dim(rng)};
    // Mostly one sign, as a band's far side is, with zeros among them.
    const double shift = 0.8 * u(rng);
    std::vector<T> v(g.size());
    for (T& x : v) x = rng() % 17 == 0 ? T(0) : T(u(rng) + shift);
    g.data = v.data();
    g.type = type;
    std::array<std::array<int, 3>, 2> box;
    for (std::size_t a = 0; a < 3; ++a) {
      std::uniform_int_distribution<int> corner(-2, g.dims[a] + 1);
      box[0][a] = corner(rng);
      box[1][a] = corner(rng);
    }
    const bool boxed = trial % 2 == 1;
    const detail::SurfaceCells cells = detail::find_surface_cells(g, boxed ? &box : nullptr);
    std::vector<std::int64_t> found;
    for (const detail::ActiveCell& c : cells.active) found.push_back(c.key);
    ASSERT_EQ(found, crossed_cells(g, v, cells.box_lo, cells.box_hi)) << "trial " << trial;
    for (std::size_t a = 0; a < 3; ++a) {
      const int most = g.dims[a] - 1;
      ASSERT_EQ(cells.box_lo[a], boxed ? std::clamp(box[0][a], 0, most) : 0);
      ASSERT_EQ(cells.box_hi[a], boxed ? std::clamp(box[1][a], cells.box_lo[a], most) : most);
    }
  }
}

}  // namespace

TEST(SurfaceCells, TheCellsWithBothSignsInAnyBoxFloat32) {
  check_random_grids<float>(ScalarType::Float32);
}

TEST(SurfaceCells, TheCellsWithBothSignsInAnyBoxFloat64) {
  check_random_grids<double>(ScalarType::Float64);
}
