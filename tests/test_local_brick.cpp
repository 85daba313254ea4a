// The local reconstruction brick by brick: any bricks give the one-brick mesh bit for bit, for
// any thread count; the mesh is closed and manifold and lies near the surface.
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "reconstruction/local/brick_reach.h"
#include "reconstruction/local/brick_stages.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/local_brick.h"
#include "test_support.h"

using namespace sdfcontour;
using test::canonical;
using test::shared_mesh_grid;

namespace {

Mesh bricked(const Grid& g, const LocalBrickOptions& o, int brick, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  return local_mesh_in_bricks(view_of(g), o, brick);
}

constexpr double kTestSag = 0.01;

// The samples [lo, hi) of `whole` copied into `values`, viewed as a block of it (what a
// BlockSource's reader returns).
GridView copied_block(const GridView& whole, const std::array<int, 3>& lo,
                      const std::array<int, 3>& hi, std::vector<double>& values) {
  GridView block = whole;
  block.first = lo;
  block.whole = whole.dims;
  for (std::size_t a = 0; a < 3; ++a) block.dims[a] = hi[a] - lo[a];
  values.clear();
  for (int i = lo[0]; i < hi[0]; ++i)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int k = lo[2]; k < hi[2]; ++k) values.push_back(whole.value(whole.index(i, j, k)));
  block.data = values.data();
  block.type = ScalarType::Float64;
  return block;
}

}  // namespace

TEST(LocalBrick, BricksEqualOneBrickBitForBit) {
  // A CSG shape (edges, corners, a hole) at 40^3, subdivided twice: bricks of 13 and 20 samples
  // cut through its features and corners.
  const Grid g = sample_grid(*make_builtin_shape("csg"), 40, Bounds{});
  LocalBrickOptions o;
  o.subdivisions = 2;
  const Mesh whole = bricked(g, o, 0, 1);
  ASSERT_GT(whole.triangles.rows(), 1000);
  test::expect_closed_and_outward(whole);
  // The join orders vertices by key and triangles by name: the same arrays, not just the same
  // mesh.
  for (const auto& [brick, threads] : {std::pair{13, 2}, std::pair{20, 1}, std::pair{0, 2}}) {
    const Mesh m = bricked(g, o, brick, threads);
    EXPECT_EQ(m.vertices, whole.vertices) << brick << " " << threads;
    EXPECT_EQ(m.triangles, whole.triangles) << brick << " " << threads;
  }
}

TEST(LocalBrick, BricksOf8And16EqualOneBrickWithTheDefaults) {
  // The command line's options (the triangulation's contact points below 64 samples per axis,
  // thin parts, two levels, carving, untangling) and the lattice's points, at 24^3: bricks of 8
  // and 16 samples, each with the halo its repairs read (most of the grid), give the one brick's
  // arrays.
  const Grid g = sample_grid(*make_builtin_shape("csg"), 24, Bounds{});
  for (const int lattice : {-1, 1}) {
    LocalBrickOptions o = local_brick_options(ContourOptions{});
    o.lattice_points = lattice;
    const Mesh whole = bricked(g, o, 0, 2);
    ASSERT_GT(whole.triangles.rows(), 1000);
    test::expect_closed_and_outward(whole);
    for (const auto& [brick, threads] : {std::pair{8, 2}, std::pair{16, 1}}) {
      const Mesh m = bricked(g, o, brick, threads);
      EXPECT_EQ(m.vertices, whole.vertices) << brick << " " << threads << " " << lattice;
      EXPECT_EQ(m.triangles, whole.triangles) << brick << " " << threads << " " << lattice;
    }
  }
}

TEST(LocalBrick, SaggingEdgesSplitAlikeInBricksAndComeCloserToTheSurface) {
  // One subdivision level, then the edges whose chords sag by more than SAG split once more:
  // bricks of 13 and 20 cut through split and unsplit edges alike (the same arrays), the mesh
  // stays closed, and it lies closer to the exact surface than without the split, with fewer
  // triangles than a second uniform level.
  const auto shape = make_builtin_shape("torus");
  const Grid g = sample_grid(*shape, 28, Bounds{});
  LocalBrickOptions o;
  o.subdivisions = 1;
  o.split_sag = kTestSag;
  // The grid's own cells and one level (on the finer grid of the thin parts, which has no level
  // left here, the split adds 22% and brings the centroids 3% closer, measured).
  o.thin_parts = 0;
  const Mesh whole = bricked(g, o, 0, 1);
  test::expect_closed_and_outward(whole);
  for (const auto& [brick, threads] : {std::pair{13, 2}, std::pair{20, 1}}) {
    const Mesh m = bricked(g, o, brick, threads);
    EXPECT_EQ(m.vertices, whole.vertices) << brick << " " << threads;
    EXPECT_EQ(m.triangles, whole.triangles) << brick << " " << threads;
  }
  o.split_sag = 0;
  const Mesh unsplit = bricked(g, o, 0, 2);
  o.subdivisions = 2;
  const Mesh uniform = bricked(g, o, 0, 2);
  EXPECT_GT(whole.triangles.rows(), unsplit.triangles.rows() * 5 / 4);
  EXPECT_LT(whole.triangles.rows(), uniform.triangles.rows() * 3 / 4);
  auto mean_error = [&](const Mesh& m) { return test::mean_centroid_distance(m, *shape); };
  EXPECT_LT(mean_error(whole), 0.8 * mean_error(unsplit));
}

TEST(LocalBrick, ThinPartsAppearAlikeInBricksAndFollowTheSurface) {
  SDFCONTOUR_REQUIRE_SHARED_MESHES();
  // The shared plane at 32^3: its wings are thinner than a spacing in places, where the samples on
  // their two sides have one sign. Without thin parts the mesh leaves those parts out; with them
  // (the grid at twice the resolution, its points between the wings' contact points inside) the
  // wings are there, in any bricks and for any thread count the same arrays.
  const Grid g = shared_mesh_grid("plane", 32);
  const double h = g.spacing().maxCoeff();
  const Mesh truth = normalize_mesh(read_mesh(SDFCONTOUR_SHARED_DIR "/data/meshes/plane.obj"), 0.9);
  const PointMatrix on_truth = sample_surface(truth, 20000, 7);
  auto missed = [&](const Mesh& m) {  // the share of the true surface over h/2 from the mesh
    const Eigen::VectorXd d = point_mesh_distances(on_truth, m);
    return double((d.array() > h / 2).count()) / double(d.size());
  };
  LocalBrickOptions o;
  o.thin_parts = 0;
  const Mesh without = bricked(g, o, 0, 2);
  o.thin_parts = 1;
  const Mesh whole = bricked(g, o, 0, 1);
  test::expect_closed_and_outward(whole);
  EXPECT_TRUE(self_intersecting_triangles(whole).empty());
  for (const auto& [brick, threads] : {std::pair{13, 2}, std::pair{20, 1}}) {
    const Mesh m = bricked(g, o, brick, threads);
    EXPECT_EQ(m.vertices, whole.vertices) << brick << " " << threads;
    EXPECT_EQ(m.triangles, whole.triangles) << brick << " " << threads;
  }
  // (Measured: 22% and 0.04%.)
  EXPECT_GT(missed(without), 0.05);
  EXPECT_LT(missed(whole), 0.01);
}

TEST(LocalBrick, Float32GridsInBricksEqualOneBrickAndReportTheirReads) {
  // Float32 values (a mapped .npy's) are copied into bricks as float32: the same mesh as one
  // brick, and each brick reports when it stops reading the grid (after its copy, and after its
  // piece; one brick that is the whole grid: before its side checks, and after its piece).
  const Grid g = sample_grid(*make_builtin_shape("csg"), 40, Bounds{});
  std::vector<float> values(g.values.data(), g.values.data() + g.values.size());
  GridView view = view_of(g);
  view.data = values.data();
  view.type = ScalarType::Float32;
  LocalBrickOptions o;
  // A narrow band and no untangling or carving: halos of 12 samples, so that bricks of 14 copy
  // blocks out of the 40^3 grid.
  o.untangle = false;
  o.carve = false;
  o.band.band = 1;
  o.band.margin = 0;
  o.split_sag = 0;   // (its ring would widen the halo by 2)
  o.thin_parts = 0;  // (and its reach)
  int reads = 0;
  o.grid_read = [&] { ++reads; };
  const Mesh whole = local_mesh_in_bricks(view, o, 0);
  EXPECT_EQ(reads, 2);
  reads = 0;
  ASSERT_LT(14 + 2 * local_brick_halo(o, g.dims), 40);
  const Mesh pieces = local_mesh_in_bricks(view, o, 14);
  EXPECT_GE(reads, 2 * 27);  // more where a brick reads a wider halo again
  ASSERT_GT(whole.triangles.rows(), 2000);
  EXPECT_EQ(pieces.vertices, whole.vertices);
  EXPECT_EQ(pieces.triangles, whole.triangles);
}

TEST(LocalBrick, GridReadBlockByBlockEqualsTheGridInMemory) {
  // A level set as a .vdb holds it (values clamped at 3 spacings, float32), read a block at a
  // time: the same arrays as the grid in memory, and the blocks that cannot hold the surface
  // (no value within 3 spacings: outside the leaves) are not read at all.
  const Grid g =
      sample_grid(*make_builtin_shape("sphere"), 40,
                  Bounds{Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5)});
  const double h = g.spacing().maxCoeff();
  std::vector<float> values(std::size_t(g.values.size()));
  for (Eigen::Index i = 0; i < g.values.size(); ++i)
    values[std::size_t(i)] = float(std::clamp(g.values[i], -3 * h, 3 * h));
  GridView view = view_of(g);
  view.data = values.data();
  view.type = ScalarType::Float32;
  LocalBrickOptions o;  // halos of 12 samples, as in the test above
  o.untangle = false;
  o.carve = false;
  o.band.band = 1;
  o.band.margin = 0;
  o.split_sag = 0;
  o.thin_parts = 0;
  o.band.truncation_mode = TruncationMode::Given;
  o.band.truncation = float(3 * h);
  const Mesh whole = local_mesh_in_bricks(view, o, 0);
  ASSERT_GT(whole.triangles.rows(), 1000);

  int reads = 0, unread = 0;
  const BlockedGrid blocked = test::blocked_grid_of(view, values, float(3 * h), reads, unread);
  const Mesh pieces = local_mesh_in_bricks(blocked, o, 10);  // 64 bricks
  EXPECT_EQ(pieces.vertices, whole.vertices);
  EXPECT_EQ(pieces.triangles, whole.triangles);
  EXPECT_GE(unread, 8);  // the corners' bricks, at least, hold no surface
  EXPECT_GE(reads, 64 - unread);
  // Its truncation cannot be found from the whole grid, which is never read at once.
  LocalBrickOptions auto_truncation;
  EXPECT_THROW(local_mesh_in_bricks(blocked, auto_truncation, 10), Error);
}

TEST(LocalBrick, ABrickReadThroughItsSourceEqualsTheGridInMemory) {
  // The bricks' driver (what the Python module and Dask call): each brick's block read through a
  // BlockSource with local_brick_halo's halo (doubled while a star needs more: no brick here
  // does), a block smaller than the grid; the piece equals the one read out of the whole grid,
  // and the block is released once read.
  const Grid g = sample_grid(*make_builtin_shape("csg"), 64, Bounds{});
  const GridView whole = view_of(g);
  LocalBrickOptions o;
  o.local.edge_fans = true;  // no repairs: a halo of a few cells and the triangulation's stars
  o.untangle = false;
  o.side_rounds = 0;
  o.band.band = 2;
  o.band.resolved = resolve_truncation(whole, o.band);
  o.band.truncation_mode = TruncationMode::Resolved;
  std::vector<double> values;
  std::vector<std::array<std::array<int, 3>, 2>> reads;
  int released = 0, with_surface = 0;
  BlockSource source;
  source.dims = g.dims;
  source.read = [&](const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    reads.push_back({lo, hi});
    return copied_block(whole, lo, hi, values);
  };
  source.release = [&] { ++released; };
  const int halo = local_brick_halo(o, g.dims);
  for (const int first : {0, 14, 27, 40, 54}) {
    const std::array<int, 3> own_first{first, 27, first}, own_end{first + 10, 37, first + 10};
    reads.clear();
    int wider = 0;
    const LocalPiece piece = local_brick_piece(source, own_first, own_end, o, &wider);
    const LocalPiece expected = local_brick_piece(whole, own_first, own_end, o);
    with_surface += piece.triangles.rows() > 0;
    EXPECT_EQ(piece.vertices, expected.vertices) << first;
    EXPECT_EQ(piece.triangles, expected.triangles) << first;
    EXPECT_EQ(piece.triangle_names, expected.triangle_names) << first;
    ASSERT_EQ(int(reads.size()), 1 + wider) << first;
    for (std::size_t r = 0; r < reads.size(); ++r)
      for (std::size_t a = 0; a < 3; ++a) {
        EXPECT_EQ(reads[r][0][a], std::max(own_first[a] - (halo << r), 0));
        EXPECT_EQ(reads[r][1][a], std::min(own_end[a] + (halo << r), g.dims[a]));
      }
    EXPECT_LT(std::size_t(reads[0][1][0] - reads[0][0][0]), std::size_t(g.dims[0])) << first;
  }
  EXPECT_GE(with_surface, 2);
  EXPECT_GE(released, with_surface);  // (a brick without surface only reads its block)
}

TEST(LocalBrick, ANonFiniteValueInTheGridOrABlockIsAnError) {
  // The whole grid is checked once, before its bricks copy their blocks; a block read through a
  // BlockSource (the Python module's and Dask's bricks) is checked as it is read.
  Grid g = sample_grid(*make_builtin_shape("torus"), 32, Bounds{});
  g.values[Eigen::Index(g.index(20, 16, 9))] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(local_mesh_in_bricks(view_of(g), LocalBrickOptions(), 12), Error);
  LocalBrickOptions o;
  o.band.truncation_mode = TruncationMode::Resolved;
  std::vector<double> values;
  BlockSource source;
  source.dims = g.dims;
  const GridView whole = view_of(g);
  source.read = [&](const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    return copied_block(whole, lo, hi, values);
  };
  try {
    local_brick_piece(source, {16, 12, 4}, {24, 20, 12}, o);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite value at [20, 16, 9]"), std::string::npos)
        << e.what();
  }
}

TEST(LocalBrick, NothingReadsTheGridAfterABrickSaysItIsDone) {
  // Values spoilt (NaN) from the first grid_read on change nothing: the bricks free their
  // copied blocks there. Default options, so the carving reads the grid before it.
  const Grid g = sample_grid(*make_builtin_shape("csg"), 32, Bounds{});
  const Mesh clean = local_mesh_in_bricks(view_of(g), LocalBrickOptions(), 0);
  Grid spoilt = g;
  LocalBrickOptions o;
  int reads = 0;
  o.grid_read = [&] {
    if (reads++ == 0) spoilt.values.setConstant(std::numeric_limits<double>::quiet_NaN());
  };
  const Mesh after = local_mesh_in_bricks(view_of(spoilt), o, 0);
  EXPECT_EQ(reads, 2);
  ASSERT_GT(clean.triangles.rows(), 1000);
  EXPECT_EQ(after.vertices, clean.vertices);
  EXPECT_EQ(after.triangles, clean.triangles);
}

TEST(LocalBrick, SharedMeshInBricksIsClosedAndNearTheSurface) {
  SDFCONTOUR_REQUIRE_SHARED_MESHES();
  const Grid g = shared_mesh_grid("wingnut", 48);
  LocalBrickOptions o;
  const Mesh whole = bricked(g, o, 0, 2), pieces = bricked(g, o, 20, 2);
  EXPECT_TRUE(canonical(whole) == canonical(pieces));
  test::expect_closed_and_outward(pieces);
  const MeshSdf sdf(
      normalize_mesh(read_mesh(SDFCONTOUR_SHARED_DIR "/data/meshes/wingnut.obj"), 0.9));
  // Mean |distance| at the triangles' centroids (a chord's worst point, not its ends), weighed
  // by the triangles' areas (the split's small triangles lie where the surface turns).
  auto mean_error = [&](const Mesh& m) {
    double sum = 0, area = 0;
    for (Eigen::Index t = 0; t < m.triangles.rows(); ++t) {
      const Eigen::Vector3d a = m.vertices.row(m.triangles(t, 0)).transpose(),
                            b = m.vertices.row(m.triangles(t, 1)).transpose(),
                            c = m.vertices.row(m.triangles(t, 2)).transpose();
      const double w = (b - a).cross(c - a).norm();
      sum += w * std::abs(sdf.distance((a + b + c) / 3));
      area += w;
    }
    return sum / area;
  };
  // (Measured: 5.5e-4 against marching cubes' 1.42e-3.)
  EXPECT_LT(mean_error(pieces), 0.6 * mean_error(marching_cubes(g)));
}

TEST(LocalBrick, BandThatReachesTheGridSides) {
  SDFCONTOUR_REQUIRE_SHARED_MESHES();
  // At 32^3 the band (8 spacings) reaches the grid's sides, where stars lie on the hull: one
  // brick certifies them as the whole set (no endless widening), bricks of 12 alike.
  const Grid g = shared_mesh_grid("armadillo", 32);
  LocalBricksStats one, twelve;
  const Mesh whole = local_mesh_in_bricks(view_of(g), LocalBrickOptions{}, 0, &one);
  const Mesh pieces = local_mesh_in_bricks(view_of(g), LocalBrickOptions{}, 12, &twelve);
  EXPECT_EQ(one.wider_halos, 0);
  EXPECT_EQ(whole.vertices, pieces.vertices);
  EXPECT_EQ(whole.triangles, pieces.triangles);
  test::expect_closed_and_outward(whole);
}

TEST(LocalBrick, QuadricVerticesDoNotMakeTheMeshCrossItself) {
  SDFCONTOUR_REQUIRE_SHARED_MESHES();
  // Near a sharp feature or a thin part the quadrics can put two cells' vertices so that their
  // triangles cross (the plane at 32^3 and the boot at 48^3, before any later move; the boot and
  // the penguin at 32^3 did until the quadric kept its rank through the robust rounds); such
  // vertices go to their crossings' mean, bricked or not.
  for (const auto& [name, n] : {std::pair{"plane", 32}, std::pair{"boot", 48}}) {
    const Grid g = shared_mesh_grid(name, n);
    LocalBrickOptions raw;
    raw.untangle = false;
    raw.project = raw.carve = false;
    raw.side_rounds = 0;
    const Mesh crossing = local_mesh_in_bricks(view_of(g), raw, 0);
    EXPECT_GT(self_intersecting_triangles(crossing).size(), 0u) << name;
    const Mesh whole = local_mesh_in_bricks(view_of(g), LocalBrickOptions{}, 0);
    const Mesh pieces = local_mesh_in_bricks(view_of(g), LocalBrickOptions{}, 12);
    EXPECT_TRUE(self_intersecting_triangles(whole).empty()) << name;
    EXPECT_EQ(whole.vertices, pieces.vertices) << name;
    EXPECT_EQ(whole.triangles, pieces.triangles) << name;
    test::expect_closed_and_outward(whole);
  }
}

TEST(LocalBrick, VerticesClampedAtTheBoxEdgesDoNotMeet) {
  // The built-in box at 48^3: cells next to its edges clamp their vertices to a shared side;
  // kept a little inside their cells, no two meet, and the mesh is free of crossings (measured:
  // 80 crossing pairs when clamped onto the sides).
  const auto box = make_builtin_shape("box");
  const Grid g = sample_grid(*box, 48, Bounds{});
  const Mesh m = local_mesh_in_bricks(view_of(g), LocalBrickOptions{}, 0);
  test::expect_closed_and_outward(m);
  EXPECT_TRUE(self_intersecting_triangles(m).empty());
}

TEST(LocalBrick, SmoothShapeInBricksIsCloseToTheSurface) {
  // A smooth shape: the bricked mesh's vertices lie within 0.02 spacings of the torus on average.
  const auto torus = make_builtin_shape("torus");
  const Grid g = sample_grid(*torus, 36, Bounds{});
  const double h = g.spacing().maxCoeff();
  const Mesh m = bricked(g, LocalBrickOptions{}, 11, 2);
  test::expect_closed_and_outward(m);
  double sum = 0;
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
    sum += std::abs(torus->distance(m.vertices.row(v).transpose()));
  EXPECT_LT(sum / double(m.vertices.rows()) / h, 0.02);
}

TEST(LocalBrick, RejectsBadBlocks) {
  const Grid g = sample_grid(*make_builtin_shape("sphere"), 12, Bounds{});
  GridView block = view_of(g);
  LocalBrickOptions o;
  o.band.truncation_mode = TruncationMode::None;
  EXPECT_THROW(local_brick_piece(block, {0, 0, 0}, {13, 4, 4}, o), Error);
  EXPECT_THROW(local_brick_piece(block, {4, 4, 4}, {4, 5, 5}, o), Error);
  LocalBrickOptions automatic;
  EXPECT_THROW(local_brick_piece(block, {0, 0, 0}, {12, 12, 12}, automatic), Error);
  o.subdivisions = 7;
  EXPECT_THROW(local_brick_piece(block, {0, 0, 0}, {12, 12, 12}, o), Error);
}

namespace {

// A piece of `keys` (ascending), vertex k at (key[0], key[1], `z`), and triangles over them.
LocalPiece piece_of(const std::vector<VertexKey>& keys, double z,
                    const std::vector<std::array<int, 3>>& triangles,
                    const std::vector<std::uint64_t>& names) {
  LocalPiece p;
  p.keys = keys;
  p.vertices.resize(Eigen::Index(keys.size()), 3);
  for (std::size_t k = 0; k < keys.size(); ++k)
    p.vertices.row(Eigen::Index(k)) << double(keys[k][0]), double(keys[k][1]), z;
  p.triangles.resize(Eigen::Index(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    p.triangles.row(Eigen::Index(t)) << triangles[t][0], triangles[t][1], triangles[t][2];
  p.triangle_names = names;
  return p;
}

}  // namespace

TEST(LocalBrick, JoinMergesSharedKeysAndOrdersTrianglesByName) {
  // Keys {0,5} and {1,0} are in both pieces; names interleave between them.
  std::vector<LocalPiece> pieces;
  pieces.push_back(piece_of({{0, 2}, {0, 5}, {1, 0}}, 0, {{0, 1, 2}, {2, 1, 0}}, {3, 10}));
  pieces.push_back(
      piece_of({{0, 5}, {1, 0}, {2, 7}, {3, 1}}, 0, {{0, 1, 2}, {1, 3, 2}, {3, 2, 0}}, {1, 4, 12}));
  const Mesh kept = join_local_pieces(pieces);
  // Vertices in ascending key order, each key once: {0,2} {0,5} {1,0} {2,7} {3,1}.
  ASSERT_EQ(kept.vertices.rows(), 5);
  const std::vector<std::array<double, 2>> expected{{0, 2}, {0, 5}, {1, 0}, {2, 7}, {3, 1}};
  for (Eigen::Index v = 0; v < 5; ++v) {
    EXPECT_EQ(kept.vertices(v, 0), expected[std::size_t(v)][0]);
    EXPECT_EQ(kept.vertices(v, 1), expected[std::size_t(v)][1]);
  }
  // Triangles by name 1, 3, 4, 10, 12, written in the joined vertices' numbers.
  TriangleMatrix want(5, 3);
  want << 1, 2, 3,  // name 1: second piece's (0, 1, 2)
      0, 1, 2,      // 3
      2, 4, 3,      // 4
      2, 1, 0,      // 10
      4, 3, 1;      // 12
  EXPECT_EQ(kept.triangles, want);
  // The overload that frees the pieces gives the same arrays.
  const Mesh freed = join_local_pieces(std::move(pieces));
  EXPECT_EQ(freed.vertices, kept.vertices);
  EXPECT_EQ(freed.triangles, kept.triangles);
  EXPECT_TRUE(pieces.empty());
}

TEST(LocalBrick, JoinOfManyLargePiecesEqualsASortedJoin) {
  // Pieces large enough to be joined in many ranges at once: 7 pieces of 3,000 to 21,000 keys,
  // each in a slab of the key space of its own that overlaps its neighbours' (as a brick's
  // halo), and names scattered over them all. The join must equal the plain one: every distinct
  // key once in ascending order, each triangle's corners renumbered, the triangles in name order.
  std::mt19937_64 random(7);
  std::vector<LocalPiece> pieces;
  std::map<VertexKey, int> all_keys;
  std::map<std::uint64_t, std::array<VertexKey, 3>> all_triangles;
  for (int p = 0; p < 7; ++p) {
    std::set<VertexKey> keys;
    const std::uint64_t low = std::uint64_t(p) * 40000;
    while (keys.size() < std::size_t(3000 * (p + 1)))
      keys.insert({low + random() % 50000, random() % 3});
    const std::vector<VertexKey> sorted(keys.begin(), keys.end());
    std::vector<std::array<int, 3>> triangles;
    std::set<std::uint64_t> names;
    while (names.size() < sorted.size()) names.insert(random() % 4000000 * 7 + std::uint64_t(p));
    for (std::size_t t = 0; t < names.size(); ++t)
      triangles.push_back({int(random() % sorted.size()), int(random() % sorted.size()),
                           int(random() % sorted.size())});
    const std::vector<std::uint64_t> name_list(names.begin(), names.end());
    pieces.push_back(piece_of(sorted, 0, triangles, name_list));
    for (const VertexKey& k : sorted) all_keys[k] = 0;
    for (std::size_t t = 0; t < triangles.size(); ++t)
      all_triangles[name_list[t]] = {sorted[std::size_t(triangles[t][0])],
                                     sorted[std::size_t(triangles[t][1])],
                                     sorted[std::size_t(triangles[t][2])]};
  }
  int next = 0;
  for (auto& [key, id] : all_keys) id = next++;
  const Mesh joined = join_local_pieces(pieces);
  ASSERT_EQ(joined.vertices.rows(), Eigen::Index(all_keys.size()));
  Eigen::Index v = 0;
  for (const auto& [key, id] : all_keys) {
    EXPECT_EQ(joined.vertices(v, 0), double(key[0])) << v;
    EXPECT_EQ(joined.vertices(v, 1), double(key[1])) << v;
    ++v;
  }
  ASSERT_EQ(joined.triangles.rows(), Eigen::Index(all_triangles.size()));
  Eigen::Index t = 0;
  for (const auto& [name, corners] : all_triangles) {
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(joined.triangles(t, c), all_keys.at(corners[std::size_t(c)])) << name;
    ++t;
  }
}

TEST(LocalBrick, JoinRejectsOneKeyPlacedTwice) {
  std::vector<LocalPiece> pieces;
  pieces.push_back(piece_of({{0, 1}, {0, 2}, {0, 3}}, 0, {{0, 1, 2}}, {0}));
  pieces.push_back(piece_of({{0, 3}, {0, 4}, {0, 5}}, 1, {{0, 1, 2}}, {1}));
  EXPECT_THROW(join_local_pieces(pieces), InternalError);
}

TEST(LocalBrick, AutoBandIsTheLocalReconstructionsOwn) {
  // A slab of the torus 130 samples long, where auto_band says 4 and auto_local_band 8: the auto
  // band's mesh is band 8's bit for bit (and not band 4's), in bricks as in one, and it gathers
  // more contact points.
  const auto shape = make_builtin_shape("torus");
  Grid g;
  g.dims = {130, 24, 24};
  const double h = 2.0 / 129;
  g.bounds.min = Eigen::Vector3d(-1, -0.3, -11.5 * h);
  g.bounds.max = g.bounds.min + h * Eigen::Vector3d(129, 23, 23);
  g.values.resize(Eigen::Index(g.size()));
  for (int i = 0; i < 130; ++i)
    for (int j = 0; j < 24; ++j)
      for (int k = 0; k < 24; ++k)
        g.values[Eigen::Index(g.index(i, j, k))] = shape->distance(g.point(i, j, k));
  LocalBrickOptions o;
  o.thin_parts = 0;
  o.lattice_points = 0;  // (the lattice's points take 6 there: below)
  LocalBricksStats auto_stats, four_stats;
  const Mesh automatic = local_mesh_in_bricks(view_of(g), o, 0, &auto_stats);
  o.band.band = 8;
  const Mesh eight = local_mesh_in_bricks(view_of(g), o, 64);
  o.band.band = 4;
  const Mesh four = local_mesh_in_bricks(view_of(g), o, 0, &four_stats);
  ASSERT_GT(automatic.triangles.rows(), 1000);
  ASSERT_EQ(automatic.vertices.rows(), eight.vertices.rows());
  ASSERT_EQ(automatic.triangles.rows(), eight.triangles.rows());
  EXPECT_EQ(automatic.vertices, eight.vertices);
  EXPECT_EQ(automatic.triangles, eight.triangles);
  EXPECT_FALSE(automatic.vertices.rows() == four.vertices.rows() &&
               automatic.vertices == four.vertices);
  EXPECT_GT(auto_stats.contact_points, four_stats.contact_points);
  // With the lattice's points (the default there) the auto band is 6's, in bricks as in one.
  o.lattice_points = 1;
  o.band.band = 0;
  const Mesh lattice = local_mesh_in_bricks(view_of(g), o, 0);
  o.band.band = 6;
  const Mesh six = local_mesh_in_bricks(view_of(g), o, 64);
  EXPECT_EQ(lattice.vertices, six.vertices);
  EXPECT_EQ(lattice.triangles, six.triangles);
}

TEST(LocalBrick, EachStageKeepsATiltedPlaneExact) {
  // The brick's stages one at a time (brick_stages.h), on a tilted plane's exact distances with
  // the defaults (thin parts' finer grid, two levels, projection, carving): the dual mesh's
  // vertices, the fit's and the bounded moves' each lie on the plane, and the undoing finds
  // nothing to undo. A stage that moved a vertex off a linear field would show here alone.
  const Eigen::Vector3d normal = Eigen::Vector3d(1, 2, 3).normalized();
  const int n = 24;
  Grid g;
  g.dims = {n, n, n};
  g.values.resize(Eigen::Index(g.size()));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        g.values[Eigen::Index(g.index(i, j, k))] = g.point(i, j, k).dot(normal) - 0.1;
  const GridView view = view_of(g);
  LocalBrickOptions o = local_brick_options(ContourOptions{});
  o.band.resolved = resolve_truncation(view, o.band);
  o.band.truncation_mode = TruncationMode::Resolved;
  ASSERT_TRUE(local_thin_parts(o, g.dims));
  auto off_plane = [&](const PointMatrix& V) {
    double worst = 0;
    for (Eigen::Index v = 0; v < V.rows(); ++v)
      worst = std::max(worst, std::abs(V.row(v).dot(normal) - 0.1));
    return worst;
  };
  const BandSamples band = select_band(view, detail::resolved_band(o, g.dims));
  const ContactPoints cp = lattice_contact_points(view, band, o.lattice_contact);
  ASSERT_GT(cp.size(), 500);
  EXPECT_LT(off_plane(cp.points), 1e-12);
  const Eigen::VectorXd depths = contact_depths(cp, band.samples.values);
  LocalPiece piece;
  const std::array<int, 3> first{0, 0, 0};
  detail::BrickDual dual = detail::brick_dual_mesh(view, band, cp, depths, first, g.dims, o, piece);
  ASSERT_EQ(dual.scale, 2);
  ASSERT_GT(dual.near.triangles.rows(), 500);
  detail::settle_dual_vertices(view, band, o, dual);
  EXPECT_LT(off_plane(dual.near.vertices), 1e-12);
  const double h = view.spacing().maxCoeff();
  detail::BrickSurface surface = detail::surface_on_contact_points(dual, cp, depths, h, g.dims, o);
  ASSERT_GT(surface.sub.mesh.triangles.rows(), 4 * dual.near.triangles.rows() - 1);
  EXPECT_LT(off_plane(surface.sub.mesh.vertices), 1e-12);
  EXPECT_LT(off_plane(surface.reconstructed), 1e-12);
  const std::vector<std::uint64_t> keys;
  detail::settle_vertices(view, band, std::nullopt, o, keys, dual, surface);
  EXPECT_LT(off_plane(surface.sub.mesh.vertices), 1e-12);
  const PointMatrix settled = surface.sub.mesh.vertices;
  detail::untangle_moves(band, h, o, surface);
  EXPECT_EQ(surface.sub.mesh.vertices, settled);
  EXPECT_TRUE(self_intersecting_triangles(surface.sub.mesh).empty());
}

// On an exact sphere (smooth at the spacing's scale), the chord offsets that put the vertices
// outside so that their flat triangles straddle the surface are kept through the sag split and
// the carving: at 64^3 the mesh's mean distance to the sphere is about 0.4x what it is without
// (where the carving pulls the vertices back onto the samples' spheres and the triangles sag
// inside), and the mesh lies on both sides of the sphere alike.
TEST(LocalBrick, ChordOffsetsKeptOnASmoothSurface) {
  const auto sphere = make_builtin_shape("sphere");
  const Grid g = sample_grid(*sphere, 64, Bounds{});
  // Mean distance and mean signed distance over the mesh's area (three points per triangle).
  auto distances = [&](const Mesh& m, double& signed_mean) {
    double area = 0, sum = 0, signed_sum = 0;
    for (Eigen::Index t = 0; t < m.triangles.rows(); ++t) {
      const Eigen::Vector3d a = m.vertices.row(m.triangles(t, 0)).transpose(),
                            b = m.vertices.row(m.triangles(t, 1)).transpose(),
                            c = m.vertices.row(m.triangles(t, 2)).transpose();
      const double w = (b - a).cross(c - a).norm() / 2;
      for (const Eigen::Vector3d& x :
           {Eigen::Vector3d((4 * a + b + c) / 6), Eigen::Vector3d((a + 4 * b + c) / 6),
            Eigen::Vector3d((a + b + 4 * c) / 6)}) {
        const double d = sphere->distance(x);
        sum += w * std::abs(d);
        signed_sum += w * d;
      }
      area += 3 * w;
    }
    signed_mean = signed_sum / area;
    return sum / area;
  };
  LocalBrickOptions o = local_brick_options(ContourOptions{});
  ASSERT_TRUE(o.keep_chord_offsets);
  const Mesh kept = bricked(g, o, 0, 2);
  o.keep_chord_offsets = false;
  const Mesh plain = bricked(g, o, 0, 2);
  double kept_signed = 0, plain_signed = 0;
  const double with = distances(kept, kept_signed), without = distances(plain, plain_signed);
  std::cout << "mean distance " << with << " (signed " << kept_signed << ") kept, " << without
            << " (signed " << plain_signed << ") not\n";
  EXPECT_LT(with, 0.7 * without);
  EXPECT_LT(std::abs(kept_signed), 0.5 * with);
  test::expect_closed_and_outward(kept);
  EXPECT_TRUE(self_intersecting_triangles(kept).empty());
}
