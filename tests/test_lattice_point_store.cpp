// The lattice's contact points kept between bricks (lattice_point_store.h): each sample's point
// made once, and taken back equal to the whole grid's.
#include <gtest/gtest.h>

#include <array>
#include <map>

#include "reconstruction/local/brick_ownership.h"
#include "reconstruction/local/lattice_point_store.h"
#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/local_brick.h"
#include "test_support.h"

using namespace sdfcontour;
using Index3 = std::array<int, 3>;

namespace {

// 1 for each core sample of `band` in the global box [lo, hi].
std::vector<char> in_box(const Grid& g, const BandSamples& band, const Index3& lo,
                         const Index3& hi) {
  std::vector<char> flags(band.core.size(), 0);
  for (std::size_t s = 0; s < flags.size(); ++s) {
    const Index3 at = detail::global_sample(g, band, s);
    bool in = band.core[s];
    for (std::size_t a = 0; a < 3; ++a) in = in && at[a] >= lo[a] && at[a] <= hi[a];
    flags[s] = in;
  }
  return flags;
}

// The band of 8 spacings, untruncated, as the bricks select it.
BandSamples band_of_eight(const Grid& g) {
  BandOptions o;
  o.band = 8;
  o.truncation_mode = TruncationMode::None;
  return select_band(g, o);
}

}  // namespace

TEST(LatticePointStore, EachSampleMadeOnceAndTakenBackAsTheWholeGrids) {
  // A CSG shape (edges, corners, a hole) at 40^3: two overlapping boxes, as two bricks' reaches.
  const Grid g = sample_grid(*make_builtin_shape("csg"), 40, Bounds{});
  const BandSamples band = band_of_eight(g);
  const ContactPointOptions o = local_brick_options(ContourOptions{}).lattice_contact;
  const ContactPoints whole = lattice_contact_points(g, band, o);
  std::map<int, int> row_of;
  for (int r = 0; r < whole.size(); ++r) row_of[whole.samples[std::size_t(r)]] = r;

  detail::LatticePointStore store;
  const Index3 lo1{0, 0, 0}, hi1{24, 39, 39}, lo2{14, 5, 0}, hi2{39, 39, 30};
  std::vector<char> first = in_box(g, band, lo1, hi1);
  EXPECT_EQ(store.take(g, band, lo1, hi1, first).size(), 0);
  const ContactPoints made1 = lattice_contact_points(g, band, o, &first);
  store.record(g, band, lo1, hi1, {13, 39, 39}, made1);  // (the second box starts at 14)

  const std::vector<char> wanted = in_box(g, band, lo2, hi2);
  std::vector<char> second = wanted;
  const ContactPoints taken = store.take(g, band, lo2, hi2, second);
  const ContactPoints made2 = lattice_contact_points(g, band, o, &second);
  // What the first box decided is not made again: the second makes only the samples beyond it.
  const std::vector<char> overlap = in_box(g, band, {14, 5, 0}, {24, 39, 30});
  long overlapping = 0;
  for (std::size_t s = 0; s < wanted.size(); ++s) {
    EXPECT_EQ(second[s], wanted[s] && !overlap[s]) << s;
    overlapping += overlap[s];
  }
  ASSERT_GT(overlapping, 1000);
  ASSERT_GT(taken.size(), 500);
  // Together, the second box's points are the whole grid's there, in band order.
  const ContactPoints both = detail::merged_contact_points(made2, taken);
  int expected = 0;
  for (std::size_t s = 0; s < wanted.size(); ++s) expected += wanted[s] && row_of.count(int(s));
  ASSERT_EQ(both.size(), expected);
  for (int q = 0; q < both.size(); ++q) {
    const int s = both.samples[std::size_t(q)];
    ASSERT_TRUE(wanted[std::size_t(s)]) << s;
    if (q > 0) {
      ASSERT_LT(both.samples[std::size_t(q - 1)], s);
    }
    const int r = row_of.at(s);
    EXPECT_EQ(both.points.row(q), whole.points.row(r)) << s;
    EXPECT_EQ(both.normals.row(q), whole.normals.row(r)) << s;
  }

  // A third box past the first's end along the first axis: the second decided what it holds.
  // (A box out of order, from 10, would read what the first did not keep.)
  std::vector<char> early = in_box(g, band, {10, 0, 0}, hi2);
  detail::LatticePointStore copy = store;
  EXPECT_THROW(copy.take(g, band, {10, 0, 0}, hi2, early), InternalError);
  store.record(g, band, lo2, hi2, {24, 39, 39}, made2);
  const Index3 lo3{25, 0, 0}, hi3{39, 39, 39};
  const std::vector<char> before = in_box(g, band, lo3, hi3);
  std::vector<char> third = before;
  const ContactPoints taken3 = store.take(g, band, lo3, hi3, third);
  long cleared = 0, left = 0;
  for (std::size_t s = 0; s < third.size(); ++s) {
    if (!before[s]) continue;
    EXPECT_EQ(third[s], !wanted[s]) << s;
    (third[s] ? left : cleared) += 1;
  }
  EXPECT_GT(cleared, 1000);
  EXPECT_GT(left, 100);
  for (int q = 0; q < taken3.size(); ++q) {
    const int r = row_of.at(taken3.samples[std::size_t(q)]);
    EXPECT_EQ(taken3.points.row(q), whole.points.row(r));
  }
}
