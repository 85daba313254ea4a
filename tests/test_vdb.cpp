#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <cmath>
#include <fstream>

#include "io/isolated_call.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/io/vdb.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

void write_grids(const std::string& path, openvdb::GridPtrVec grids) {
  openvdb::initialize();
  openvdb::io::File(path).write(grids);
}

// A scene of two level-set spheres of `radius` (voxels of `voxel`), at the origin and at `at`,
// written as the grid "surface".
void write_two_spheres(const std::string& path, double voxel, double radius,
                       const openvdb::Vec3f& at) {
  auto scene = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
      float(radius), openvdb::Vec3f(0, 0, 0), float(voxel), 3.f);
  auto other = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(radius), at,
                                                                        float(voxel), 3.f);
  openvdb::tools::csgUnion(*scene, *other);
  scene->setName("surface");
  write_grids(path, {scene});
}

void expect_error(const std::string& path, const std::string& grid, const std::string& needle) {
  try {
    read_vdb_level_set(path, grid);
    ADD_FAILURE() << path << " was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

// The built-in torus sampled on 33^3 over a box off the origin, written as a level set of half
// width 3 voxels into a fresh folder named `name`.
struct TorusLevelSet {
  std::string path;
  Grid grid;
};
TorusLevelSet torus_level_set(const std::string& name) {
  TorusLevelSet t;
  t.path = (test::temp_dir(name) / "torus.vdb").string();
  Bounds bounds;
  bounds.min = Eigen::Vector3d(-1.0, -0.9, -0.8);
  bounds.max = bounds.min + Eigen::Vector3d::Constant(2.0);
  t.grid = sample_grid(*make_builtin_shape("torus"), 33, bounds);
  write_vdb_level_set(t.path, t.grid, 3.0);
  return t;
}

}  // namespace

// sample -> .vdb -> samples: the active voxels are the grid samples inside the band, at their
// world positions, with their values (as float32).
TEST(Vdb, RoundTripKeepsTheBandSparse) {
  const TorusLevelSet t = torus_level_set("vdb_roundtrip");
  const std::string& path = t.path;
  const Grid& grid = t.grid;
  const Bounds& bounds = grid.bounds;
  const double h = grid.spacing()[0];
  const VdbLevelSet ls = read_vdb_level_set(path);
  EXPECT_EQ(ls.grid_name, "surface");
  EXPECT_NEAR(ls.voxel_size, h, 1e-12);
  EXPECT_NEAR(ls.background, 3 * h, 1e-6);
  long expected = 0;
  for (Eigen::Index i = 0; i < grid.values.size(); ++i)
    expected += std::abs(float(grid.values[i])) < float(3 * h);
  ASSERT_EQ(ls.samples.values.size(), expected);
  EXPECT_LT(expected, grid.values.size() / 4);
  for (Eigen::Index r = 0; r < ls.samples.values.size(); ++r) {
    const Eigen::Vector3d p = ls.samples.points.row(r).transpose();
    const Eigen::Vector3d ijk = (p - bounds.min) / h;
    const Eigen::Vector3i c = ijk.array().round().cast<int>();
    ASSERT_LT((ijk - c.cast<double>()).norm(), 1e-6);
    EXPECT_EQ(ls.samples.values[r],
              double(float(grid.values[Eigen::Index(grid.index(c[0], c[1], c[2]))])));
  }
  // GCP on the level set: its background is the truncation distance.
  const SdfInput input = ScatteredInput{ls.samples, ls.voxel_size};
  ContourOptions o;
  o.band.truncation_mode = TruncationMode::Given;
  o.band.truncation = ls.background;
  o.poisson.depth = 7;
  const ContourResult r = contour(input, o);
  const auto torus = make_builtin_shape("torus");
  double worst = 0;
  for (Eigen::Index i = 0; i < r.mesh->vertices.rows(); ++i)
    worst = std::max(worst, std::abs(torus->distance(r.mesh->vertices.row(i).transpose())));
  EXPECT_LT(worst, 0.5 * h);
}

// Box by box: the layout names the active voxels' box and leaves, and a box read gives each
// voxel's value (active: the grid's float32 value; inactive: the background with the sign of
// the side it is on), read from the part of the file it needs.
TEST(Vdb, BoxReadsGiveEveryVoxelsValue) {
  const TorusLevelSet t = torus_level_set("vdb_box");
  const std::string& path = t.path;
  const Grid& grid = t.grid;
  const Bounds& bounds = grid.bounds;
  const double h = grid.spacing()[0];
  const VdbLayout layout = read_vdb_layout(path);
  EXPECT_EQ(layout.grid_name, "surface");
  EXPECT_NEAR(layout.voxel_size, h, 1e-12);
  EXPECT_NEAR((layout.origin - bounds.min).norm(), 0, 1e-12);
  EXPECT_FALSE(layout.leaf_origins.empty());
  const float background = float(3 * h);
  // A box across the band's edge: all of it, and a corner of it.
  for (const std::array<int, 3>& first :
       {std::array<int, 3>{0, 0, 0}, std::array<int, 3>{9, 4, 20}}) {
    const std::array<int, 3> dims = {33 - first[0], 29 - first[1], 13};
    const std::vector<float> box = read_vdb_box(path, "", first, dims);
    std::size_t at = 0;
    for (int i = 0; i < dims[0]; ++i)
      for (int j = 0; j < dims[1]; ++j)
        for (int k = 0; k < dims[2]; ++k, ++at) {
          const float v = float(
              grid.values[Eigen::Index(grid.index(first[0] + i, first[1] + j, first[2] + k))]);
          const float expected = std::abs(v) < background ? v : std::copysign(background, v);
          ASSERT_EQ(box[at], expected) << i << " " << j << " " << k;
        }
  }
  EXPECT_THROW(read_vdb_box(path, "", {0, 0, 0}, {0, 4, 4}), Error);
  EXPECT_THROW(read_vdb_layout(path, "density"), Error);
}

TEST(Vdb, RejectsWhatIsNotAFloatLevelSet) {
  const auto dir = test::temp_dir("vdb_bad");
  const std::string d = dir.string() + "/";
  std::ofstream(d + "junk.vdb") << "this is not a vdb file at all";
  expect_error(d + "junk.vdb", "", "not a .vdb file");
  expect_error(d + "missing.vdb", "", "cannot read");
  auto ints = openvdb::Int32Grid::create(0);
  ints->setName("labels");
  ints->tree().setValue(openvdb::Coord(1, 2, 3), 7);
  write_grids(d + "ints.vdb", {ints});
  expect_error(d + "ints.vdb", "", "no float grid");
  auto fog = openvdb::FloatGrid::create(0.f);
  fog->setName("density");
  fog->setGridClass(openvdb::GRID_FOG_VOLUME);
  fog->tree().setValue(openvdb::Coord(0, 0, 0), 0.5f);
  write_grids(d + "fog.vdb", {fog});
  expect_error(d + "fog.vdb", "", "not a level set");
  expect_error(d + "fog.vdb", "surface", "no float grid named 'surface'");
  auto empty = openvdb::FloatGrid::create(0.1f);
  empty->setGridClass(openvdb::GRID_LEVEL_SET);
  write_grids(d + "empty.vdb", {empty});
  expect_error(d + "empty.vdb", "", "no active voxels");
  // Truncated: the header is fine, the rest is cut off.
  const Grid grid = sample_grid(*make_builtin_shape("sphere"), 16, Bounds{});
  write_vdb_level_set(d + "whole.vdb", grid, 3.0);
  std::ifstream in(d + "whole.vdb", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(d + "cut.vdb", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  expect_error(d + "cut.vdb", "", "cannot read");
}

// OpenVDB trusts its input; its reader runs isolated, so hostile files end as IoError. The two
// files are fuzz findings (tests/fuzz/fuzz_vdb.cpp): a string length of 1.7 GB that OpenVDB
// allocated, and a byte read as a bool (undefined behaviour in OpenVDB's RootNode). Then every
// 61st byte of a real level set is flipped, one at a time: each read succeeds or throws Error.
TEST(Vdb, HostileFilesEndAsErrors) {
  const std::string corpus = SDFCONTOUR_SOURCE_DIR "/tests/fuzz/corpus/vdb/";
  for (const char* name : {"huge_string_length.vdb", "invalid_bool.vdb"})
    EXPECT_THROW(read_vdb_level_set(corpus + name), IoError) << name;
  const auto dir = test::temp_dir("vdb_hostile");
  const std::string path = dir.string() + "/x.vdb";
  const Grid grid = sample_grid(*make_builtin_shape("sphere"), 12, Bounds{});
  write_vdb_level_set(path, grid, 2.0);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  int refused = 0, read = 0;
  for (std::size_t at = 8; at < bytes.size(); at += 61) {
    std::string bad = bytes;
    bad[at] = char(~bad[at]);
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bad;
    try {
      const VdbLevelSet s = read_vdb_level_set(path);
      EXPECT_GT(s.samples.values.size(), 0);
      ++read;
    } catch (const Error&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 0);
  EXPECT_GT(read + refused, 100);
}

// Level sets far apart in one file (a scene): read sparse, bricked by their samples, one Poisson
// solve per object, so time and memory follow the active voxels, not the 10^6 voxels between
// them. A stray voxel 10^9 voxels away is dropped as isolated, never sized into a grid.
TEST(Vdb, FarApartLevelSetsCostTheirVoxelsOnly) {
  openvdb::initialize();
  const auto dir = test::temp_dir("vdb_far");
  const double voxel = 0.05, radius = 0.6;
  for (const double apart : {1e5, 1e6}) {
    SCOPED_TRACE(apart);
    const std::string path = (dir / "scene.vdb").string();
    write_two_spheres(path, voxel, radius, openvdb::Vec3f(float(apart * voxel), 0, 0));
    const VdbLevelSet ls = read_vdb_level_set(path);
    ContourOptions o;
    o.band.truncation_mode = TruncationMode::Given;
    o.band.truncation = ls.background;
    const ContourResult r = contour(ScatteredInput{ls.samples, ls.voxel_size}, o);
    int near = 0, far = 0;
    for (Eigen::Index i = 0; i < r.mesh->vertices.rows(); ++i) {
      Eigen::Vector3d p = r.mesh->vertices.row(i).transpose();
      const bool is_far = p.x() > apart * voxel / 2;
      if (is_far) p.x() -= apart * voxel;
      (is_far ? far : near) += 1;
      EXPECT_LT(std::abs(p.norm() - radius), 0.25 * voxel);
    }
    EXPECT_GT(near, 100);
    EXPECT_GT(far, 100);
  }
  // A handful of voxels and one stray far away: the stray is dropped, the rest contoured at once.
  auto few = openvdb::FloatGrid::create(3 * float(voxel));
  few->setGridClass(openvdb::GRID_LEVEL_SET);
  few->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
  few->setName("surface");
  for (const auto& c :
       {openvdb::Coord(0, 0, 0), openvdb::Coord(1, 0, 0), openvdb::Coord(0, 1, 0),
        openvdb::Coord(0, 0, 1), openvdb::Coord(1, 1, 0), openvdb::Coord(1000000000, 0, 0)})
    few->tree().setValue(c, c.x() > 0 && c.y() > 0 ? -0.01f : 0.02f);
  const std::string path = (dir / "few.vdb").string();
  write_grids(path, {few});
  const VdbLevelSet ls = read_vdb_level_set(path);
  EXPECT_EQ(ls.samples.values.size(), 6);
  ContourOptions o;
  o.poisson.depth = 5;
  const ContourResult r = contour(ScatteredInput{ls.samples, ls.voxel_size}, o);
  EXPECT_EQ(r.isolated_samples, 1);
  EXPECT_LT(r.mesh->vertices.cwiseAbs().maxCoeff(), 4 * voxel);
}

TEST(Vdb, FarApartLevelSetsReadBoxByBoxCostTheirLeavesOnly) {
  // Two spheres 1e5 voxels apart on the diagonal: 4e4 bricks of 256 per axis span the box, and
  // only those that meet a leaf are visited (the local reconstruction and marching cubes alike);
  // at 1e6 apart the box outgrows the local reconstruction's vertex names: refused in one line.
  openvdb::initialize();
  const auto dir = test::temp_dir("vdb_far_boxes");
  const double voxel = 0.05, radius = 0.6;
  for (const double apart : {1e5, 1e6}) {
    SCOPED_TRACE(apart);
    const float far = float(apart * voxel);
    const std::string path = (dir / "scene.vdb").string();
    write_two_spheres(path, voxel, radius, openvdb::Vec3f(far, far, far));
    VdbLayout layout;
    BlockedGridInput input{vdb_blocked_grid(path, "", &layout), 0, std::nullopt};
    input.truncation = layout.background;
    for (const Method method : {Method::Gcp, Method::Mc}) {
      ContourOptions o;
      o.method = method;
      if (method == Method::Gcp && apart > 1e5) {
        EXPECT_THROW(contour(input, o), Error);
        continue;
      }
      const ContourResult r = contour(input, o);
      int near = 0, away = 0;
      for (Eigen::Index i = 0; i < r.mesh->vertices.rows(); ++i) {
        Eigen::Vector3d p = r.mesh->vertices.row(i).transpose();
        const bool is_far = p.x() > far / 2;
        if (is_far) p -= Eigen::Vector3d::Constant(far);
        (is_far ? away : near) += 1;
        EXPECT_LT(std::abs(p.norm() - radius), 0.5 * voxel);
      }
      EXPECT_GT(near, 100) << int(method);
      EXPECT_GT(away, 100) << int(method);
    }
  }
}

namespace {

// The exact distance to a box of half sides `half` centred at `centre` (world space).
double box_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& centre,
                    const Eigen::Vector3d& half) {
  const Eigen::Vector3d q = (p - centre).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// A level set of an off-centre box, written with `xform` and the background `background` (in
// voxels; a level set's is +3).
void write_box_level_set(const std::string& path, openvdb::math::Transform::Ptr xform,
                         const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double voxel,
                         float background = 3) {
  auto grid = openvdb::FloatGrid::create(background * float(voxel));
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  grid->setTransform(xform);
  grid->setName("surface");
  auto accessor = grid->getAccessor();
  const int reach = int(std::ceil((half.norm() + centre.norm() + 4 * voxel) / voxel));
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -reach; k <= reach; ++k) {
        const openvdb::Vec3d w = xform->indexToWorld(openvdb::Coord(i, j, k));
        const double d = box_distance(Eigen::Vector3d(w[0], w[1], w[2]), centre, half);
        if (std::abs(d) < 3 * voxel) accessor.setValue(openvdb::Coord(i, j, k), float(d));
      }
  openvdb::tools::signedFloodFill(grid->tree());
  // (The fill takes the background's magnitude; a file can still hold another.)
  grid->tree().root().setBackground(background * float(voxel), /*updateChildNodes=*/false);
  write_grids(path, {grid});
}

}  // namespace

// A level set whose transform rotates and offsets it: every path puts the surface where the
// transform says (the box-by-box reader contours in the grid's frame, then places the mesh).
TEST(Vdb, RotatedTransformsPlaceTheMeshInTheWorld) {
  const auto dir = test::temp_dir("vdb_rotated");
  const std::string path = (dir / "rotated.vdb").string();
  const double voxel = 0.025;
  auto xform = openvdb::math::Transform::createLinearTransform(voxel);
  xform->preRotate(0.5, openvdb::math::Z_AXIS);
  xform->preRotate(0.3, openvdb::math::X_AXIS);
  xform->postTranslate(openvdb::Vec3d(0.1, -0.2, 0.3));
  const Eigen::Vector3d centre(0.15, 0.05, 0.25), half(0.3, 0.2, 0.12);
  write_box_level_set(path, xform, centre, half, voxel);
  VdbLayout layout;
  BlockedGrid grid = vdb_blocked_grid(path, "", &layout);
  ASSERT_TRUE(vdb_world_from_grid(layout));
  std::array<double, 2> mean{};  // mc, gcp
  for (int m = 0; m < 2; ++m) {
    ContourOptions options;
    options.method = m == 0 ? Method::Mc : Method::Gcp;
    const ContourResult r =
        contour(BlockedGridInput{grid, layout.background, vdb_world_from_grid(layout)}, options);
    ASSERT_TRUE(r.mesh && r.mesh->vertices.rows() > 0) << m;
    double worst = 0;
    for (Eigen::Index v = 0; v < r.mesh->vertices.rows(); ++v) {
      const double d = std::abs(box_distance(r.mesh->vertices.row(v).transpose(), centre, half));
      worst = std::max(worst, d);
      mean[std::size_t(m)] += d / double(r.mesh->vertices.rows());
    }
    EXPECT_LT(worst, 0.5 * voxel) << m;  // (a misplaced mesh would be a whole offset off)
    test::expect_closed_and_outward(*r.mesh);
  }
  // Unplaced, the mesh would lie the transform's offset (10 voxels and more) away.
  EXPECT_LT(mean[0], 0.05 * voxel);
  EXPECT_LT(mean[1], 0.05 * voxel);
  // The sparse reader (the Poisson path) agrees on where the samples are.
  const VdbLevelSet sparse = read_vdb_level_set(path);
  for (Eigen::Index s = 0; s < sparse.samples.points.rows(); s += 97)
    EXPECT_NEAR(box_distance(sparse.samples.points.row(s).transpose(), centre, half),
                sparse.samples.values[s], 1e-6);
}

TEST(Vdb, BackgroundsNoLevelSetHasAndShearedVoxelsAreRefused) {
  const auto dir = test::temp_dir("vdb_background");
  const double voxel = 0.05;
  const Eigen::Vector3d centre(0, 0, 0), half(0.3, 0.3, 0.3);
  for (float background : {0.f, -3.f}) {
    const std::string path = (dir / "background.vdb").string();
    write_box_level_set(path, openvdb::math::Transform::createLinearTransform(voxel), centre, half,
                        voxel, background);
    for (int reader = 0; reader < 2; ++reader) try {
        if (reader == 0) read_vdb_layout(path);
        if (reader == 1) read_vdb_level_set(path);
        ADD_FAILURE() << "background " << background << " accepted by reader " << reader;
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("background"), std::string::npos) << e.what();
      }
  }
  openvdb::math::Mat4d shear = openvdb::math::Mat4d::identity();
  shear.setToScale(openvdb::Vec3d(voxel));
  shear(1, 0) = 0.3 * voxel;
  const std::string path = (dir / "sheared.vdb").string();
  write_box_level_set(path, openvdb::math::Transform::createLinearTransform(shear), centre, half,
                      voxel);
  EXPECT_THROW(vdb_blocked_grid(path), Error);
}

// A reader child that never runs (it waits on a lock that another thread held when it was forked)
// is started once more; one that spends its processor time is not.
TEST(IsolatedCall, AStalledChildIsStartedOnceMore) {
  const auto dir = test::temp_dir("isolated_stall");
  const std::string marker = (dir / "first").string();
  detail::IsolationLimits limits;
  limits.seconds = 0.1;  // the parent waits 4 x 0.1 + 10 s
  const std::string reply = detail::run_isolated(
      [&]() -> std::string {
        if (!std::filesystem::exists(marker)) {
          std::ofstream(marker) << "stalled";
          for (;;) ::pause();  // no processor time: a stall
        }
        return "ran";
      },
      "the test's child", limits);
  EXPECT_EQ(reply, "ran");
  // A child that spins is killed by its processor-time limit, once.
  EXPECT_THROW(detail::run_isolated(
                   []() -> std::string {
                     for (volatile std::uint64_t i = 0;; i = i + 1) {
                     }
                   },
                   "the test's spinning child", limits),
               IoError);
}
