// Points bucketed in cubes (point_cubes.h): the points within a radius, and the order in which
// the anchored cubes give them (the projection sums its rows in that order, in any brick).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "reconstruction/point_cubes.h"

using namespace sdfcontour;

namespace {

PointMatrix random_points(int count, double from, double to, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(from, to);
  PointMatrix P(count, 3);
  for (int i = 0; i < count; ++i) P.row(i) << u(rng), u(rng), u(rng);
  return P;
}

std::vector<int> within(const detail::PointCubes& cubes, const PointMatrix& P,
                        const Eigen::Vector3d& p, double r) {
  std::vector<int> buffer;
  const int count = cubes.collect_within(P, p, r * r, 1, buffer);
  return std::vector<int>(buffer.begin(), buffer.begin() + count);
}

}  // namespace

// Each query's points are exactly the brute-force scan's, and a subset of the points in a box (a
// brick's, its rows in the same relative order) gets the whole set's points in that box in the
// same order: the anchored cubes are the space's, wherever the subset starts.
TEST(PointCubes, AnchoredCubesGiveAnySubsetItsPointsInTheWholeSetsOrder) {
  const double r = 0.05;
  const PointMatrix P = random_points(60000, -1, 1, 7);
  std::vector<int> sub_rows;  // the subset: the points with x > 0.13 (a brick's side)
  for (int i = 0; i < int(P.rows()); ++i)
    if (P(i, 0) > 0.13) sub_rows.push_back(i);
  const PointMatrix S = P(sub_rows, Eigen::all);
  const detail::PointCubes whole(P, r, true), part(S, r, true);
  ASSERT_TRUE(whole.anchored() && part.anchored());
  const PointMatrix queries = random_points(500, 0.2, 1, 11);
  int nonempty = 0;
  for (int q = 0; q < int(queries.rows()); ++q) {
    const Eigen::Vector3d p = queries.row(q).transpose();
    const std::vector<int> all = within(whole, P, p, r);
    std::vector<int> brute;
    for (int i = 0; i < int(P.rows()); ++i)
      if ((P.row(i).transpose() - p).squaredNorm() <= r * r) brute.push_back(i);
    std::vector<int> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    ASSERT_EQ(sorted, brute);
    // The subset's answer, named by the whole set's rows; the whole set's, kept to the subset.
    std::vector<int> from_part, from_whole;
    for (const int i : within(part, S, p, r)) from_part.push_back(sub_rows[std::size_t(i)]);
    for (const int i : all)
      if (P(i, 0) > 0.13) from_whole.push_back(i);
    ASSERT_EQ(from_part, from_whole) << "query " << q;
    nonempty += !from_part.empty();
  }
  EXPECT_GT(nonempty, 400);
}
