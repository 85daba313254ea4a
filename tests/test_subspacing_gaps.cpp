#include <algorithm>
#include <cmath>
#include <functional>

#include "sdfcontour/band/subspacing_gaps.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

// The grid (nx, ny, nz) of f over the box from the origin with unit spacing.
Grid unit_grid(int nx, int ny, int nz, const std::function<double(const Eigen::Vector3d&)>& f) {
  Grid g;
  g.dims = {nx, ny, nz};
  g.bounds.min = Eigen::Vector3d::Zero();
  g.bounds.max = Eigen::Vector3d(nx - 1, ny - 1, nz - 1);
  g.values.resize(Eigen::Index(g.size()));
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) g.values[Eigen::Index(g.index(i, j, k))] = f(g.point(i, j, k));
  return g;
}

// The exact signed distance to the box around `center` with half sides `half`.
double box_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& center,
                    const Eigen::Vector3d& half) {
  const Eigen::Vector3d q = (p - center).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

}  // namespace

TEST(SubspacingGaps, APlateBetweenTwoSampleLayersIsOneGapPerEdgeAcrossIt) {
  // A plate 0.3 spacings thick midway between x = 5 and x = 6: each of the 8 x 8 edges across it
  // has both samples outside at 0.35, the field rising by a spacing beyond them.
  const Grid plate =
      unit_grid(12, 8, 8, [](const Eigen::Vector3d& p) { return std::abs(p.x() - 5.5) - 0.15; });
  SubspacingGaps c = count_subspacing_gaps(view_of(plate));
  EXPECT_EQ(c.gaps, 64);
  EXPECT_EQ(c.crossings, 0);
  // A slot of outside through a solid: the same edges, inside.
  const Grid slot =
      unit_grid(12, 8, 8, [](const Eigen::Vector3d& p) { return 0.15 - std::abs(p.x() - 5.5); });
  c = count_subspacing_gaps(view_of(slot));
  EXPECT_EQ(c.gaps, 64);
  EXPECT_EQ(c.crossings, 0);
}

TEST(SubspacingGaps, PlanesAndThickPlatesHaveNone) {
  // A plane near the samples and a plate 2.2 spacings thick: sign changes, no gap (the field
  // along a tangent edge is flat, across the plate monotone between its samples).
  const Grid plane = unit_grid(12, 8, 8, [](const Eigen::Vector3d& p) { return p.x() - 5.3; });
  SubspacingGaps c = count_subspacing_gaps(view_of(plane));
  EXPECT_EQ(c.gaps, 0);
  EXPECT_EQ(c.crossings, 64);
  const Grid thick =
      unit_grid(12, 8, 8, [](const Eigen::Vector3d& p) { return std::abs(p.x() - 5.5) - 1.1; });
  c = count_subspacing_gaps(view_of(thick));
  EXPECT_EQ(c.gaps, 0);
  EXPECT_EQ(c.crossings, 128);
  // Values times value_scale are the distances: halved values make the thick plate's edges
  // look like a thin part's where their samples' scaled values leave a gap.
  const Grid half = unit_grid(
      12, 8, 8, [](const Eigen::Vector3d& p) { return 0.5 * (std::abs(p.x() - 5.5) - 0.15); });
  EXPECT_EQ(count_subspacing_gaps(view_of(half), 2.0).gaps, 64);
  EXPECT_EQ(count_subspacing_gaps(view_of(half), 1.0).gaps, 0);  // rises by half a spacing only
}

TEST(SubspacingGaps, BlocksThatOwnDisjointPartsSumToTheWholeGrid) {
  // Plates across each axis, a ball of a spacing's radius and a box: gaps and crossings alike.
  const Grid g = unit_grid(23, 19, 21, [](const Eigen::Vector3d& p) {
    double d = std::abs(p.x() - 7.5) - 0.2;
    d = std::min(d, std::abs(p.y() - 11.4) - 0.1);
    d = std::min(d, std::abs(p.z() - 3.6) - 0.25);
    d = std::min(d, (p - Eigen::Vector3d(15.3, 5.2, 14.7)).norm() - 0.9);
    return std::min(d, box_distance(p, {12.2, 9.1, 10.6}, {3.3, 2.4, 4.1}));
  });
  const SubspacingGaps whole = count_subspacing_gaps(view_of(g));
  EXPECT_GT(whole.gaps, 300);
  EXPECT_GT(whole.crossings, 200);
  SubspacingGaps sum;
  const std::array<int, 3> cut{9, 10, 6};
  for (int b = 0; b < 8; ++b) {
    std::array<int, 3> own_first{}, own_end{}, first{}, end{};
    for (int a = 0; a < 3; ++a) {
      const bool high = b >> a & 1;
      own_first[a] = high ? cut[a] : 0;
      own_end[a] = high ? g.dims[a] : cut[a];
      first[a] = std::max(own_first[a] - 1, 0);
      end[a] = std::min(own_end[a] + 2, g.dims[a]);
    }
    Grid block;
    block.bounds = g.bounds;
    for (int a = 0; a < 3; ++a) block.dims[a] = end[a] - first[a];
    block.values.resize(Eigen::Index(block.size()));
    for (int i = 0; i < block.dims[0]; ++i)
      for (int j = 0; j < block.dims[1]; ++j)
        for (int k = 0; k < block.dims[2]; ++k)
          block.values[Eigen::Index(block.index(i, j, k))] =
              g.values[Eigen::Index(g.index(first[0] + i, first[1] + j, first[2] + k))];
    GridView view = view_of(block);
    view.first = first;
    view.whole = g.dims;
    const SubspacingGaps c = count_subspacing_gaps(view, own_first, own_end);
    sum.gaps += c.gaps;
    sum.crossings += c.crossings;
    if (b == 7) {
      // Without the sample before its owned ones the block cannot count.
      const std::array<int, 3> earlier{own_first[0] - 1, own_first[1], own_first[2]};
      EXPECT_THROW(count_subspacing_gaps(view, earlier, own_end), Error);
    }
  }
  EXPECT_EQ(sum.gaps, whole.gaps);
  EXPECT_EQ(sum.crossings, whole.crossings);

  // The same grid read a block at a time (as a .vdb level set is), in bricks of 5 and 8: the
  // same counts, with the bricks that hold no value within 2 spacings left unread.
  std::vector<float> values(g.values.data(), g.values.data() + g.values.size());
  GridView as_float = view_of(g);
  as_float.data = values.data();
  as_float.type = ScalarType::Float32;
  const SubspacingGaps float_whole = count_subspacing_gaps(as_float);
  int reads = 0, unread = 0;
  const BlockedGrid blocked = test::blocked_grid_of(as_float, values, 2.0f, reads, unread);
  for (const int brick : {5, 8}) {
    const SubspacingGaps c = count_subspacing_gaps(blocked, 1.0, brick);
    EXPECT_EQ(c.gaps, float_whole.gaps) << brick;
    EXPECT_EQ(c.crossings, float_whole.crossings) << brick;
  }
  EXPECT_GT(unread, 0);
  EXPECT_GT(reads, 0);
}

TEST(SubspacingGaps, FineGridsLookForThinPartsWhereTheyHaveThem) {
  // 192 samples along x, where the size alone leaves thin parts off: a block with a fin 0.4
  // spacings thick between two sample layers. Its gaps make auto look for thin parts, and the fin
  // appears (vertices on its faces); without them it does not. The block alone has no gap, and
  // auto then builds the mesh without thin parts, bit for bit.
  const Eigen::Vector3d fin_center(120.5, 9.5, 9.5), fin_half(0.2, 5, 5);
  auto block = [](const Eigen::Vector3d& p) {
    return box_distance(p, {40, 9.5, 9.5}, {20.3, 5.2, 5.3});
  };
  const Grid with_fin = unit_grid(192, 20, 20, [&](const Eigen::Vector3d& p) {
    return std::min(block(p), box_distance(p, fin_center, fin_half));
  });
  auto run = [](const Grid& g, Switch thin_parts) {
    ContourOptions o;
    o.thin_parts = thin_parts;
    return contour(grid_input(g), o);
  };
  auto fin_vertices = [&](const Mesh& m) {
    int count = 0;
    for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
      count += std::abs(box_distance(m.vertices.row(v).transpose(), fin_center, fin_half)) < 0.05;
    return count;
  };
  const ContourResult found = run(with_fin, Switch::Auto);
  ASSERT_TRUE(found.subspacing_gaps);
  EXPECT_EQ(found.subspacing_gaps->gaps, 10 * 10);  // the fin's edges across x
  ASSERT_TRUE(found.local_bricks);
  EXPECT_TRUE(found.local_bricks->thin_parts);
  EXPECT_GT(fin_vertices(*found.mesh), 200);
  const MeshTopology topology = mesh_topology(*found.mesh);
  EXPECT_TRUE(topology.closed && topology.consistently_oriented);
  EXPECT_EQ(topology.nonmanifold_edges, 0);
  const ContourResult off = run(with_fin, Switch::Off);
  EXPECT_EQ(fin_vertices(*off.mesh), 0);

  const Grid alone = unit_grid(192, 20, 20, block);
  const ContourResult plain = run(alone, Switch::Auto);
  ASSERT_TRUE(plain.subspacing_gaps);
  EXPECT_EQ(plain.subspacing_gaps->gaps, 0);
  EXPECT_FALSE(plain.local_bricks->thin_parts);
  const Mesh without = *run(alone, Switch::Off).mesh;
  EXPECT_EQ(plain.mesh->vertices, without.vertices);
  EXPECT_EQ(plain.mesh->triangles, without.triangles);
}

TEST(SubspacingGaps, ChooseThinPartsFrom192To256SamplesPerAxis) {
  EXPECT_TRUE(auto_thin_parts(191, SubspacingGaps{0, 1000}));  // below 192: always
  EXPECT_TRUE(auto_thin_parts(256, SubspacingGaps{25, 10000}));
  EXPECT_FALSE(auto_thin_parts(256, SubspacingGaps{24, 10000}));  // under 0.25% of the crossings
  // The shared meshes at 256^3: the boot's tread (0.38%) on, the plane (0.13%) off.
  EXPECT_TRUE(auto_thin_parts(256, SubspacingGaps{439, 114168}));
  EXPECT_FALSE(auto_thin_parts(256, SubspacingGaps{51, 39352}));
  EXPECT_FALSE(auto_thin_parts(200, SubspacingGaps{0, 0}));
  EXPECT_FALSE(auto_thin_parts(257, SubspacingGaps{1000, 1000}));  // the finer grid's memory
  // Beyond 256 contour() counts no gaps: a fin on a grid 257 samples long stays out.
  const Grid g = unit_grid(257, 12, 12, [](const Eigen::Vector3d& p) {
    return std::min(box_distance(p, {60, 5.5, 5.5}, {30.3, 3.2, 3.3}),
                    box_distance(p, {200.5, 5.5, 5.5}, {0.2, 3, 3}));
  });
  const ContourResult r = contour(grid_input(g), ContourOptions{});
  EXPECT_FALSE(r.subspacing_gaps);
  ASSERT_TRUE(r.local_bricks);
  EXPECT_FALSE(r.local_bricks->thin_parts);
  EXPECT_EQ(count_subspacing_gaps(view_of(g)).gaps, 6 * 6);  // (which it would have found)
}
