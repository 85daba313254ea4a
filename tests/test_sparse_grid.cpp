// A grid held only near its surface (input/sparse_grid.h) gives what the dense grid gives: the
// band, the sign changes, marching cubes and GCP's Poisson mesh and contact points, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/sdf_input.h"
#include "sdfcontour/input/signed_distance.h"
#include "sdfcontour/input/sparse_grid.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "test_support.h"

using namespace sdfcontour;
using test::canonical;

namespace {

// `dense` held as its bricks of `brick` cells within `reach` (world units) of the surface (a
// brick is kept when its smallest |value| is at most `reach`); the others filled with their
// smallest |value|, signed. The blocks' values live in `storage`.
struct Sparse {
  SparseGridInput input;
  std::vector<std::shared_ptr<std::vector<double>>> storage;
};
Sparse sparse_of(const Grid& dense, int brick, double reach) {
  Sparse s;
  SparseGrid& g = s.input.grid;
  g.dims = dense.dims;
  g.bounds = dense.bounds;
  g.brick = brick;
  for (int a = 0; a < 3; ++a) g.bricks[std::size_t(a)] = bricks_along(dense.dims[a], brick);
  for (int a = 0; a < g.bricks[0]; ++a)
    for (int b = 0; b < g.bricks[1]; ++b)
      for (int c = 0; c < g.bricks[2]; ++c) {
        const std::array<int, 3> first{a * brick, b * brick, c * brick};
        std::array<int, 3> dims;
        for (int x = 0; x < 3; ++x)
          dims[std::size_t(x)] = std::min(brick, dense.dims[x] - 1 - first[std::size_t(x)]) + 1;
        auto values = std::make_shared<std::vector<double>>();
        double smallest = INFINITY, sign = 1;
        for (int i = 0; i < dims[0]; ++i)
          for (int j = 0; j < dims[1]; ++j)
            for (int k = 0; k < dims[2]; ++k) {
              const double v =
                  dense.values[Eigen::Index(dense.index(first[0] + i, first[1] + j, first[2] + k))];
              values->push_back(v);
              if (std::abs(v) < smallest) smallest = std::abs(v), sign = v < 0 ? -1 : 1;
            }
        if (smallest > reach) {
          g.block_of.push_back(-1);
          g.fill.push_back(sign * smallest);
          continue;
        }
        GridView block;
        block.dims = dims;
        block.first = first;
        block.whole = dense.dims;
        block.bounds = dense.bounds;
        block.data = values->data();
        g.block_of.push_back(int(g.blocks.size()));
        g.fill.push_back(0);
        g.blocks.push_back(block);
        s.storage.push_back(values);
      }
  return s;
}

Grid torus_grid(int n) {
  return sample_grid(*make_builtin_shape("torus"), n, Bounds{});
}

}  // namespace

TEST(SparseGrid, BandSignChangesAndMarchingCubesAreTheDenseGrids) {
  const Grid dense = torus_grid(45);
  const double h = dense.spacing().maxCoeff();
  const Sparse s = sparse_of(dense, 8, 9 * h);
  const SparseGrid& g = s.input.grid;
  ASSERT_LT(g.blocks.size(), g.fill.size());  // some bricks are left out
  validate_sparse_grid(g);
  BandOptions band;
  band.band = 8;
  const BandSamples a = select_band(dense, band), b = select_band(g, band);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.core, b.core);
  EXPECT_TRUE(a.samples.points == b.samples.points);
  EXPECT_TRUE(a.samples.values == b.samples.values);
  EXPECT_EQ(sign_change_edges(view_of(dense)), sign_change_edges(g));
  EXPECT_EQ(canonical(marching_cubes(dense)), canonical(marching_cubes(g)));
  EXPECT_FALSE(sides_inside(g));
  for (int i : {0, 7, 8, 22, 44})
    EXPECT_EQ(g.value(i, 22, 30), dense.values[Eigen::Index(dense.index(i, 22, 30))]);
}

TEST(SparseGrid, GcpPoissonMeshAndContactPointsAreTheDenseGrids) {
  const Grid dense = torus_grid(40);
  const double h = dense.spacing().maxCoeff();
  ContourOptions options;
  options.reconstruction = Reconstruction::Poisson;
  options.want_points = true;
  options.band.band = 3;  // a given band: no wider carving band
  const Sparse s = sparse_of(dense, 4, (contour_values_reach(options, dense.dims) + 1) * h);
  ASSERT_LT(s.input.grid.blocks.size(), s.input.grid.fill.size());
  const ContourResult a = contour(grid_input(dense), options);
  const ContourResult b = contour(s.input, options);
  ASSERT_TRUE(a.mesh && b.mesh);
  EXPECT_EQ(canonical(*a.mesh), canonical(*b.mesh));
  EXPECT_TRUE(a.contact_points->points == b.contact_points->points);
  EXPECT_TRUE(a.contact_points->normals == b.contact_points->normals);
  test::expect_closed_and_outward(*b.mesh);
}

TEST(SparseGrid, BadGridsAreRefusedWithTheirPlace) {
  const Grid dense = torus_grid(20);
  Sparse s = sparse_of(dense, 8, 3.0);
  SparseGrid& g = s.input.grid;
  ASSERT_FALSE(g.blocks.empty());
  (*s.storage[0])[5] = NAN;
  try {
    validate_sparse_grid(g);
    FAIL() << "a NaN was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
  }
  (*s.storage[0])[5] = 1;
  g.blocks[0].dims[0] -= 1;
  EXPECT_THROW(validate_sparse_grid(g), Error);
  g.blocks[0].dims[0] += 1;
  g.fill.pop_back();
  EXPECT_THROW(validate_sparse_grid(g), Error);
  g.fill.push_back(1);
  // No sign change: every stored value and fill positive.
  std::fill(g.fill.begin(), g.fill.end(), 1.0);
  for (auto& values : s.storage) std::fill(values->begin(), values->end(), 0.5);
  EXPECT_THROW(require_sign_change(g), Error);
  ContourOptions options;
  options.reconstruction = Reconstruction::Poisson;
  EXPECT_THROW(contour(s.input, options), Error);
}
