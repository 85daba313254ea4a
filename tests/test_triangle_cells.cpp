// Boxes listed per cube (triangle_cells.h): every query and pair sweep against a brute-force scan
// over the boxes' cube ranges.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <map>
#include <mutex>
#include <random>
#include <set>

#include "reconstruction/triangle_cells.h"

using namespace sdfcontour::detail;

namespace {

bool overlap(const TriangleCells::Range& a, const TriangleCells::Range& b) {
  for (std::size_t d = 0; d < 3; ++d)
    if (a.hi[d] < b.lo[d] || b.hi[d] < a.lo[d]) return false;
  return true;
}

// Random boxes in [0, 1]^3, most small, some spanning many cubes; their ranges on `grid`.
std::vector<TriangleCells::Range> random_ranges(const CellGrid& grid, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> where(0, 1), size(0, 0.05), big(0, 0.6);
  std::vector<TriangleCells::Range> ranges;
  for (int b = 0; b < count; ++b) {
    const Eigen::Vector3d lo(where(rng), where(rng), where(rng));
    const double s = b % 17 == 0 ? big(rng) : size(rng);
    ranges.push_back({grid.cube_of(lo), grid.cube_of(lo + Eigen::Vector3d::Constant(s))});
  }
  return ranges;
}

}  // namespace

TEST(TriangleCells, EachBoxMeetingARangeOnce) {
  const CellGrid grid = CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 0.07, 1e9);
  ASSERT_EQ(grid.n[0], 15);
  const auto ranges = random_ranges(grid, 600, 3);
  const TriangleCells cells(grid, ranges);
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> cube(0, grid.n[0] - 1);
  for (int q = 0; q < 300; ++q) {
    TriangleCells::Range r;
    for (std::size_t d = 0; d < 3; ++d) {
      const int a = cube(rng), b = cube(rng);
      r.lo[d] = std::min(a, b), r.hi[d] = q % 3 == 0 ? r.lo[d] : std::max(a, b);
    }
    std::map<int, int> seen;
    cells.for_each_in(r, [&](int b) { ++seen[b]; });
    for (int b = 0; b < int(ranges.size()); ++b) {
      const bool meets = overlap(ranges[std::size_t(b)], r);
      EXPECT_EQ(seen.count(b) ? seen[b] : 0, meets ? 1 : 0) << "box " << b << " query " << q;
    }
  }
}

TEST(TriangleCells, EachPairSharingACubeOnce) {
  const CellGrid grid = CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 0.05, 1e9);
  const auto ranges = random_ranges(grid, 800, 5);
  const TriangleCells cells(grid, ranges);
  std::map<std::pair<int, int>, int> seen;
  std::mutex lock;
  cells.for_each_pair([&](int a, int b) {
    const std::lock_guard<std::mutex> hold(lock);
    EXPECT_LT(a, b);
    ++seen[std::make_pair(a, b)];
  });
  std::size_t expected = 0;
  for (int a = 0; a < int(ranges.size()); ++a)
    for (int b = a + 1; b < int(ranges.size()); ++b) {
      if (!overlap(ranges[std::size_t(a)], ranges[std::size_t(b)])) continue;
      ++expected;
      EXPECT_EQ(seen[std::make_pair(a, b)], 1) << a << " " << b;
    }
  EXPECT_EQ(seen.size(), expected);
  EXPECT_GT(expected, 100u);  // (the boxes do meet)
}

TEST(TriangleCells, CoarserCubesWhereTooManyColumns) {
  // 1000 x 1000 columns asked for, at most 10^4 allowed: cubes 16 times larger (63 x 63).
  const CellGrid grid =
      CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 0.001, 1e4);
  EXPECT_DOUBLE_EQ(grid.cell, 0.016);
  EXPECT_EQ(grid.n[0], 63);
  EXPECT_LE(double(grid.n[0]) * grid.n[1], 1e4);
  EXPECT_EQ(grid.index(-5, 0), 0);
  EXPECT_EQ(grid.index(5, 0), 62);
  EXPECT_EQ(grid.index(std::nan(""), 1), 0);
  // No finite length: one cube, which every box and query reads.
  const CellGrid whole =
      CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, INFINITY, 1), 0.1, 1e4);
  EXPECT_EQ(whole.n, (std::array<int, 3>{1, 1, 1}));
  EXPECT_EQ(whole.index(1e300, 0), 0);
  EXPECT_EQ(CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 0.0, 1e4).n[2], 1);
}

TEST(TriangleCells, TheSameListsForAnyThreadCount) {
  const CellGrid grid = CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 0.05, 1e9);
  const auto ranges = random_ranges(grid, 3000, 9);
  auto visits = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const TriangleCells cells(grid, ranges);
    std::vector<int> order;
    cells.for_each_in({{0, 0, 0}, {grid.n[0] - 1, grid.n[1] - 1, grid.n[2] - 1}},
                      [&](int b) { order.push_back(b); });
    return order;
  };
  const std::vector<int> one = visits(1);
  EXPECT_EQ(one.size(), ranges.size());
  EXPECT_EQ(one, visits(2));
}

TEST(TriangleCells, FarApartPartsKeepOnlyTheirColumns) {
  // Two clusters of small boxes 10^6 cubes apart along x and y: 10^12 columns, of which the boxes
  // occupy a few hundred; queries and pairs as over a dense grid.
  const CellGrid grid =
      CellGrid::over(Eigen::Vector3d::Zero(), Eigen::Vector3d(1e6, 1e6, 1), 1.0, INFINITY);
  ASSERT_GT(double(grid.n[0]) * grid.n[1], 1e12);
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> near(0, 9), size(0, 1);
  std::vector<TriangleCells::Range> ranges;
  for (int b = 0; b < 400; ++b) {
    const int base = b % 2 ? 999990 : 0;
    TriangleCells::Range r;
    for (std::size_t d = 0; d < 3; ++d) {
      r.lo[d] = d == 2 ? near(rng) % 2 : base + near(rng);
      r.hi[d] = std::min(r.lo[d] + size(rng), grid.n[d] - 1);
    }
    ranges.push_back(r);
  }
  const TriangleCells cells(grid, ranges);
  std::size_t pairs = 0, expected = 0;
  std::mutex lock;
  cells.for_each_pair([&](int a, int b) {
    const std::lock_guard<std::mutex> hold(lock);
    EXPECT_TRUE(overlap(ranges[std::size_t(a)], ranges[std::size_t(b)]));
    ++pairs;
  });
  for (std::size_t a = 0; a < ranges.size(); ++a)
    for (std::size_t b = a + 1; b < ranges.size(); ++b) expected += overlap(ranges[a], ranges[b]);
  EXPECT_EQ(pairs, expected);
  for (const TriangleCells::Range& q :
       {TriangleCells::Range{{0, 0, 0}, {5, 5, 1}},
        TriangleCells::Range{{999995, 999992, 0}, {999999, 999999, 0}},
        TriangleCells::Range{{500000, 0, 0}, {500001, 1, 1}}}) {
    std::map<int, int> seen;
    cells.for_each_in(q, [&](int b) { ++seen[b]; });
    for (int b = 0; b < int(ranges.size()); ++b)
      EXPECT_EQ(seen.count(b) ? seen[b] : 0, overlap(ranges[std::size_t(b)], q) ? 1 : 0);
  }
}
