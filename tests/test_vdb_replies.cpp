// The reading child's replies (src/io/vdb_replies.h), and level sets at the ends of OpenVDB's
// index range, which the grid around them would overflow.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <climits>
#include <cmath>

#include "io/vdb_replies.h"
#include "sdfcontour/io/vdb.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

detail::OpenVdbLayout two_leaf_layout() {
  detail::OpenVdbLayout l;
  l.grid_name = "surface";
  for (int a = 0; a < 3; ++a) l.min[a] = -9 + a, l.max[a] = 12 + a;
  l.voxel = 0.05;
  l.origin[0] = 1, l.origin[1] = 2, l.origin[2] = 3;
  l.background = 0.15;
  l.leaf_origins = {-16, -8, -8, 8, 8, 8};
  return l;
}

// Throws Error (of type E) whose message holds `needle`.
template <class E = Error>
void expect_refused(const std::string& bytes, const std::string& needle) {
  try {
    detail::parse_layout_reply(bytes, "f.vdb");
    ADD_FAILURE() << "accepted a reply that should hold " << needle;
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

// A float level set with one 6^3 block of active voxels from index `first` along x.
std::string block_at(const std::string& name, int first) {
  openvdb::initialize();
  auto grid = openvdb::FloatGrid::create(3.0f);
  grid->setName("far");
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
  auto values = grid->getAccessor();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k)
        values.setValue(
            openvdb::Coord(first + i, j, k),
            float(std::sqrt((i - 2.5) * (i - 2.5) + (j - 2.5) * (j - 2.5) + (k - 2.5) * (k - 2.5)) -
                  2.0));
  const std::string path = (test::temp_dir("vdb_index_range") / name).string();
  openvdb::io::File(path).write({grid});
  return path;
}

}  // namespace

// A layout goes through its bytes unchanged, and its grid holds every leaf.
TEST(VdbReplies, ALayoutRoundTripsAndItsGridHoldsItsLeaves) {
  const detail::OpenVdbLayout l = two_leaf_layout();
  const VdbLayout back = detail::parse_layout_reply(detail::layout_reply(l), "f.vdb");
  EXPECT_EQ(back.grid_name, "surface");
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(back.min[std::size_t(a)], l.min[a]);
    EXPECT_EQ(back.max[std::size_t(a)], l.max[a]);
  }
  EXPECT_EQ(back.voxel_size, 0.05);
  EXPECT_EQ(back.origin, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(back.rotation, Eigen::Matrix3d::Identity());
  EXPECT_EQ(back.background, 0.15);
  ASSERT_EQ(back.leaf_origins.size(), 2u);
  EXPECT_EQ(back.leaf_origins[1], (std::array<int, 3>{8, 8, 8}));
  const BlockedGrid grid = detail::blocked_grid_of(back, "f.vdb");
  for (std::size_t a = 0; a < 3; ++a) {
    // The active voxels' box grown by a voxel: 12 + a - (-9 + a) + 3 samples.
    EXPECT_EQ(grid.dims[a], 24);
    EXPECT_DOUBLE_EQ(grid.bounds.min[a], back.origin[Eigen::Index(a)] + 0.05 * (-10 + int(a)));
  }
  for (const SampleBox& box : *grid.surface_boxes)
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_GE(box.lo[a], -6);
      EXPECT_LE(box.hi[a], grid.dims[a] + 6);
    }
}

// Bytes cut short or too long, and leaves outside the active voxels, are the reader's fault
// (InternalError); boxes at the ends of the index range, inverted boxes, degenerate transforms
// and backgrounds that are no half width are the file's (Error, naming it).
TEST(VdbReplies, MalformedOrOutOfRangeLayoutsAreRefused) {
  const std::string good = detail::layout_reply(two_leaf_layout());
  expect_refused<InternalError>(good.substr(0, good.size() - 1), "reply");
  expect_refused<InternalError>(good + "x", "reply");
  expect_refused<InternalError>(std::string(), "cut short");
  auto refused = [](void (*change)(detail::OpenVdbLayout&), const std::string& needle,
                    bool internal = false) {
    detail::OpenVdbLayout l = two_leaf_layout();
    change(l);
    const std::string bytes = detail::layout_reply(l);
    if (internal)
      expect_refused<InternalError>(bytes, needle);
    else
      expect_refused<Error>(bytes, needle);
  };
  refused([](detail::OpenVdbLayout& l) { l.min[0] = INT_MIN; }, "index range");
  refused([](detail::OpenVdbLayout& l) { l.max[2] = INT_MAX - 3; }, "index range");
  refused([](detail::OpenVdbLayout& l) { l.min[1] = 20; }, "no active voxels");
  refused([](detail::OpenVdbLayout& l) { l.voxel = 0; }, "degenerate transform");
  refused([](detail::OpenVdbLayout& l) { l.origin[1] = NAN; }, "degenerate transform");
  refused([](detail::OpenVdbLayout& l) { l.rotation[1] = 0.5; }, "degenerate transform");
  refused([](detail::OpenVdbLayout& l) { l.background = -1; }, "background");
  refused([](detail::OpenVdbLayout& l) { l.leaf_origins[3] = 13; }, "leaf", true);
  refused([](detail::OpenVdbLayout& l) { l.leaf_origins[0] = -17; }, "leaf", true);
  refused([](detail::OpenVdbLayout& l) { l.leaf_origins.pop_back(); }, "malformed", true);
}

// A level set's points go through their bytes unchanged; a reply of the wrong size is refused.
TEST(VdbReplies, ALevelSetRoundTripsAndAWrongSizeIsRefused) {
  VdbLevelSet s;
  s.grid_name = "ls";
  s.voxel_size = 0.1;
  s.background = 0.3;
  s.samples.points.resize(2, 3);
  s.samples.points << 0, 0, 0, 0.1, 0.2, 0.3;
  s.samples.values.resize(2);
  s.samples.values << -0.05, 0.05;
  const std::string bytes = detail::level_set_reply(s);
  const VdbLevelSet back = detail::parse_level_set_reply(bytes);
  EXPECT_EQ(back.grid_name, "ls");
  EXPECT_EQ(back.voxel_size, 0.1);
  EXPECT_EQ(back.background, 0.3);
  EXPECT_EQ(back.samples.points, s.samples.points);
  EXPECT_EQ(back.samples.values, s.samples.values);
  EXPECT_THROW(detail::parse_level_set_reply(bytes.substr(0, bytes.size() - 8)), InternalError);
  EXPECT_THROW(detail::parse_level_set_reply(bytes + std::string(8, '\0')), InternalError);
  const VdbLevelSet none = detail::parse_level_set_reply(detail::level_set_reply(VdbLevelSet{}));
  EXPECT_EQ(none.samples.values.size(), 0);
}

// A level set whose voxels reach the ends of OpenVDB's index range (int) is refused with an error:
// the grid around it, a voxel wider, would overflow (it did, in vdb_blocked_grid). One just inside
// reads as any other; a box read past the range's end is refused before the reader starts.
TEST(VdbReplies, LevelSetsAtTheEndsOfTheIndexRangeAreRefused) {
  for (int first : {INT_MIN, INT_MAX - 5}) {
    const std::string path = block_at(first < 0 ? "low.vdb" : "high.vdb", first);
    try {
      vdb_blocked_grid(path);
      ADD_FAILURE() << "voxels from " << first << " accepted";
    } catch (const InternalError& e) {
      ADD_FAILURE() << "an internal error for a file's content: " << e.what();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("index range"), std::string::npos) << e.what();
    }
  }
  const int first = INT_MIN + 100;
  const std::string path = block_at("inside.vdb", first);
  VdbLayout layout;
  const BlockedGrid grid = vdb_blocked_grid(path, "", &layout);
  EXPECT_EQ(layout.min[0], first);
  EXPECT_EQ(grid.dims[0], 8);  // 6 voxels and one on each side
  const std::vector<float> values = read_vdb_box(path, "", {first, 0, 0}, {6, 6, 6});
  EXPECT_NEAR(values[0], std::sqrt(3 * 2.5 * 2.5) - 2.0, 1e-6);
  EXPECT_THROW(read_vdb_box(path, "", {INT_MAX - 2, 0, 0}, {4, 4, 4}), Error);
}
