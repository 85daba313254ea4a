// Marching cubes brick by brick: the joined pieces are the whole grid's mesh, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <tuple>
#include <vector>

#include "sdfcontour/extraction/brick_marching.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "test_support.h"

using namespace sdfcontour;
using test::canonical;

namespace {

// The samples [first, first + dims) of `grid`, as a grid of their own (float32 if asked).
struct Block {
  std::vector<double> f64;
  std::vector<float> f32;
  GridView view;
};
Block block_of(const Grid& grid, std::array<int, 3> first, std::array<int, 3> dims, bool single) {
  Block b;
  for (int i = 0; i < dims[0]; ++i)
    for (int j = 0; j < dims[1]; ++j)
      for (int k = 0; k < dims[2]; ++k) {
        const double v =
            grid.values[Eigen::Index(grid.index(first[0] + i, first[1] + j, first[2] + k))];
        b.f64.push_back(v);
        b.f32.push_back(float(v));
      }
  b.view.dims = dims;
  b.view.type = single ? ScalarType::Float32 : ScalarType::Float64;
  b.view.data = single ? static_cast<const void*>(b.f32.data()) : b.f64.data();
  return b;
}

// Cuts the grid's cells into bricks of `side` cells (the last ones shorter) and joins the pieces.
Mesh bricked(const Grid& grid, int side, bool single) {
  std::vector<MeshPiece> pieces;
  for (int i = 0; i + 1 < grid.dims[0]; i += side)
    for (int j = 0; j + 1 < grid.dims[1]; j += side)
      for (int k = 0; k + 1 < grid.dims[2]; k += side) {
        const std::array<int, 3> first{i, j, k};
        std::array<int, 3> dims;
        for (int a = 0; a < 3; ++a)
          dims[std::size_t(a)] = std::min(side, grid.dims[a] - 1 - first[a]) + 1;
        const Block b = block_of(grid, first, dims, single);
        pieces.push_back(marching_cubes_brick(b.view, grid, first));
      }
  return join_mesh_pieces(pieces);
}

// The grid with float32-rounded values, so that the whole-grid run sees what a float32 block does.
Grid rounded(Grid g) {
  for (Eigen::Index p = 0; p < g.values.size(); ++p) g.values[p] = double(float(g.values[p]));
  return g;
}

}  // namespace

TEST(BrickMarching, JoinedPiecesAreTheWholeGridsMeshBitForBit) {
  SDFCONTOUR_REQUIRE_SHARED_MESHES();
  // wingnut: thin parts and sharp edges cut by the seams; bricks of 7 and 16 cells, the last
  // ones shorter, in float64 and float32.
  const Grid grid = test::shared_mesh_grid("wingnut", 37);
  for (const bool single : {false, true}) {
    const Grid whole = single ? rounded(grid) : grid;
    const Mesh expected = marching_cubes(whole);
    ASSERT_GT(expected.triangles.rows(), 1000);
    for (const int side : {7, 16}) {
      SCOPED_TRACE("side " + std::to_string(side) + (single ? " float32" : " float64"));
      const Mesh joined = bricked(whole, side, single);
      EXPECT_EQ(canonical(joined), canonical(expected));
      const MeshTopology t = mesh_topology(joined);
      EXPECT_TRUE(t.closed && t.consistently_oriented);
    }
  }
}

TEST(BrickMarching, GridReadBlockByBlockGivesTheWholeGridsMesh) {
  SDFCONTOUR_REQUIRE_SHARED_MESHES();
  // wingnut clamped at 3 spacings, as a level set holds it, read a block at a time (bricks of 6
  // and 9 cells): marching cubes of the grid in memory, the blocks far from the surface unread.
  const Grid grid = test::shared_mesh_grid("wingnut", 37);
  const double h = grid.spacing().maxCoeff();
  std::vector<float> values(std::size_t(grid.values.size()));
  for (Eigen::Index i = 0; i < grid.values.size(); ++i)
    values[std::size_t(i)] = float(std::clamp(grid.values[i], -3 * h, 3 * h));
  Grid clamped = grid;
  for (Eigen::Index i = 0; i < grid.values.size(); ++i) clamped.values[i] = values[std::size_t(i)];
  const Mesh expected = marching_cubes(clamped);
  GridView view = view_of(grid);
  view.data = values.data();
  view.type = ScalarType::Float32;
  for (const int side : {6, 9}) {
    int reads = 0, unread = 0;
    const BlockedGrid blocked = test::blocked_grid_of(view, values, float(3 * h), reads, unread);
    EXPECT_EQ(canonical(marching_cubes(blocked, side)), canonical(expected)) << side;
    EXPECT_GT(unread, 0) << side;
    EXPECT_GT(reads, 0) << side;
  }
}

TEST(BrickMarching, AmbiguousFacesAndCentroidsAgreeAcrossSeams) {
  // Random signs: most faces ambiguous, many polygons that need a centroid vertex.
  Grid grid;
  grid.dims = {15, 14, 13};
  grid.bounds.min = Eigen::Vector3d(-0.3, 0.1, 2.0);
  grid.bounds.max = Eigen::Vector3d(0.9, 0.7, 3.1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  grid.values.resize(Eigen::Index(grid.size()));
  for (auto& v : grid.values) v = u(rng);
  const Mesh expected = marching_cubes(grid);
  for (const int side : {1, 2, 5}) {
    SCOPED_TRACE("side " + std::to_string(side));
    EXPECT_EQ(canonical(bricked(grid, side, false)), canonical(expected));
  }
}

TEST(BrickMarching, RefusesBadBricks) {
  Grid grid;
  grid.dims = {8, 8, 8};
  grid.values = Eigen::VectorXd::Constant(512, 1.0);
  grid.values[Eigen::Index(grid.index(5, 6, 7))] = std::nan("");
  const Block b = block_of(grid, {4, 4, 4}, {4, 4, 4}, false);
  try {
    marching_cubes_brick(b.view, grid, {4, 4, 4});
    FAIL() << "a NaN was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "the grid has a non-finite value at [5, 6, 7]");
  }
  EXPECT_THROW(marching_cubes_brick(b.view, grid, {5, 4, 4}), Error);   // past the grid
  EXPECT_THROW(marching_cubes_brick(b.view, grid, {-1, 4, 4}), Error);  // before it
  const Block flat = block_of(grid, {0, 0, 0}, {1, 4, 4}, false);
  EXPECT_THROW(marching_cubes_brick(flat.view, grid, {0, 0, 0}), Error);
}

TEST(BrickMarching, JoinRefusesOneKeyAtTwoPositions) {
  MeshPiece a, b;
  a.keys = {3};
  a.vertices = PointMatrix::Zero(1, 3);
  b.keys = {3};
  b.vertices = PointMatrix::Ones(1, 3);
  EXPECT_THROW(join_mesh_pieces({a, b}), InternalError);
  b.vertices = PointMatrix::Zero(1, 3);
  EXPECT_EQ(join_mesh_pieces({a, b}).vertices.rows(), 1);
}
