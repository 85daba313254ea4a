// Self-intersections: the detector against CGAL's (Polygon Mesh Processing), undoing the moves
// that cross a mesh, and GCP's meshes of thin shapes free of crossings.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include <random>

#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "test_patches.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

const std::string kMeshes = SDFCONTOUR_SHARED_DIR "/data/meshes/";

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;

// CGAL's own list of crossing pairs (face indices are our triangle rows), ascending.
std::vector<std::pair<int, int>> cgal_pairs(const Mesh& mesh) {
  SurfaceMesh sm;
  std::vector<SurfaceMesh::Vertex_index> v;
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
    v.push_back(sm.add_vertex({mesh.vertices(i, 0), mesh.vertices(i, 1), mesh.vertices(i, 2)}));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const auto f =
        sm.add_face(v[std::size_t(mesh.triangles(t, 0))], v[std::size_t(mesh.triangles(t, 1))],
                    v[std::size_t(mesh.triangles(t, 2))]);
    EXPECT_EQ(int(f), int(t));
  }
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> found;
  CGAL::Polygon_mesh_processing::self_intersections(sm, std::back_inserter(found));
  std::vector<std::pair<int, int>> pairs;
  for (const auto& [a, b] : found)
    pairs.emplace_back(std::min(int(a), int(b)), std::max(int(a), int(b)));
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// Marching cubes' mesh of a built-in shape (free of crossings), its vertices moved at random by
// up to `noise` spacings.
Mesh noisy_mesh(const std::string& shape, int n, double noise, unsigned seed,
                Mesh* clean = nullptr) {
  const Grid grid = sample_grid(*make_builtin_shape(shape), n, Bounds{});
  Mesh mesh = marching_cubes(grid);
  if (clean) *clean = mesh;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = grid.spacing()[0];
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
    for (int a = 0; a < 3; ++a) mesh.vertices(i, a) += noise * h * u(rng);
  return mesh;
}

}  // namespace

// The same pairs as CGAL's self_intersections on a torus whose vertices were moved at random
// (and none on the clean mesh). Flagging some triangles keeps exactly the pairs they are in.
TEST(SelfIntersections, TheSamePairsAsCgal) {
  Mesh clean;
  const Mesh mesh = noisy_mesh("torus", 24, 0.6, 3, &clean);
  EXPECT_TRUE(self_intersecting_triangles(clean).empty());
  const auto ours = self_intersecting_triangles(mesh);
  EXPECT_GT(ours.size(), 20u);
  EXPECT_EQ(ours, cgal_pairs(mesh));
  // Every triangle watched takes the triangle-by-triangle search (the unwatched one goes cube by
  // cube): the same pairs.
  const std::vector<char> every(std::size_t(mesh.triangles.rows()), 1);
  EXPECT_EQ(self_intersecting_triangles(mesh, &every), ours);
  std::vector<char> watch(std::size_t(mesh.triangles.rows()), 0);
  for (std::size_t t = 0; t < watch.size(); t += 2) watch[t] = 1;
  std::vector<std::pair<int, int>> expected;
  for (const auto& p : ours)
    if (watch[std::size_t(p.first)] || watch[std::size_t(p.second)]) expected.push_back(p);
  EXPECT_EQ(self_intersecting_triangles(mesh, &watch), expected);
  watch.pop_back();
  EXPECT_THROW(self_intersecting_triangles(mesh, &watch), Error);
}

// Pairs that share a vertex whose star projects one to one along its normal are not tested (they
// meet only in what they share): the same pairs as CGAL's whatever the noise, from none to
// folds throughout, on a torus and a sphere.
TEST(SelfIntersections, StarsThatProjectOneToOneSkipNoCrossing) {
  for (const char* shape : {"torus", "sphere"})
    for (const double noise : {0.2, 0.35, 0.5, 0.8})
      for (const unsigned seed : {1u, 2u}) {
        const Mesh mesh = noisy_mesh(shape, 20, noise, seed);
        EXPECT_EQ(self_intersecting_triangles(mesh), cgal_pairs(mesh))
            << shape << " noise " << noise << " seed " << seed;
      }
}

// A flat patch whose vertices moved within its plane (coplanar to the last bit, as a face aligned
// with the grid is, where no floating-point filter decides): folded fans overlap. The same pairs
// as CGAL's, on a plane of constant z and on a tilted one; none while every move is small.
TEST(SelfIntersections, AFlatPatchFoldedInItsPlaneFindsTheSamePairsAsCgal) {
  const int n = 24;
  const double step = 0.1;
  auto patch = [&](double noise, bool tilted, unsigned seed) {
    Mesh m = test::flat_patch(n, step, 0.25);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
      const double x = m.vertices(v, 0) + noise * step * u(rng);
      const double y = m.vertices(v, 1) + noise * step * u(rng);
      m.vertices.row(v) << x, y, tilted ? 0.5 * x - 0.25 * y : 0.25;
    }
    return m;
  };
  for (const bool tilted : {false, true}) {
    EXPECT_TRUE(self_intersecting_triangles(patch(0.2, tilted, 3)).empty());
    const Mesh folded = patch(0.7, tilted, 5);
    const auto ours = self_intersecting_triangles(folded);
    EXPECT_GT(ours.size(), 20u) << "tilted " << tilted;
    EXPECT_EQ(ours, cgal_pairs(folded)) << "tilted " << tilted;
  }
}

// Parts far apart against their triangles' size (more cubes than a 64-bit key holds at the
// triangles' scale): the same pairs as CGAL's, in each of three copies of the noisy torus.
TEST(SelfIntersections, PartsFarApartFindTheSamePairs) {
  const Mesh one = noisy_mesh("torus", 16, 0.6, 5);
  Mesh far;
  const Eigen::Index v = one.vertices.rows(), t = one.triangles.rows();
  far.vertices.resize(3 * v, 3);
  far.triangles.resize(3 * t, 3);
  for (int c = 0; c < 3; ++c) {
    far.vertices.middleRows(c * v, v) = one.vertices;
    far.vertices.middleRows(c * v, v).col(c) += Eigen::VectorXd::Constant(v, 1e14);
    far.triangles.middleRows(c * t, t) = one.triangles.array() + int(c * v);
  }
  const auto pairs = self_intersecting_triangles(far);
  EXPECT_GT(pairs.size(), 30u);
  EXPECT_EQ(pairs, cgal_pairs(far));
}

// Two triangles that share one vertex cross where an opposite edge cuts the other triangle, as
// CGAL counts them: pierced, or coplanar and overlapping; not where one lies on one side of the
// other's plane (the shortcut most neighbours take).
TEST(SelfIntersections, TrianglesSharingAVertex) {
  auto pair_with = [](double x1, double y1, double z1, double x2, double y2, double z2) {
    Mesh m;
    m.vertices.resize(5, 3);
    m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, x1, y1, z1, x2, y2, z2;
    m.triangles.resize(2, 3);
    m.triangles << 0, 1, 2, 0, 3, 4;
    return m;
  };
  const std::vector<std::pair<int, int>> both{{0, 1}}, none;
  const Mesh pierced = pair_with(0.3, 0.3, -1, 0.3, 0.3, 1);
  const Mesh above = pair_with(0.3, 0.3, 0.5, 0.2, 0.6, 1);
  const Mesh overlapping = pair_with(0.5, 0.2, 0, 0.2, 0.5, 0);
  const Mesh beside = pair_with(-0.5, 0.2, 0, -0.2, -0.5, 0);
  EXPECT_EQ(self_intersecting_triangles(pierced), both);
  EXPECT_EQ(self_intersecting_triangles(above), none);
  EXPECT_EQ(self_intersecting_triangles(overlapping), both);
  EXPECT_EQ(self_intersecting_triangles(beside), none);
  for (const Mesh* m : {&pierced, &above, &overlapping, &beside})
    EXPECT_EQ(self_intersecting_triangles(*m), cgal_pairs(*m));
}

// Two triangles that share an edge overlap when they fold onto each other (coplanar, on the same
// side of the edge), as CGAL counts them; unfolded, or bent out of the plane, they do not.
TEST(SelfIntersections, TrianglesFoldedOntoTheirSharedEdgeOverlap) {
  Mesh fold;
  fold.vertices.resize(4, 3);
  fold.vertices << 0, 0, 0, 1, 0, 0, 0.3, 1, 0, 0.6, 0.8, 0;
  fold.triangles.resize(2, 3);
  fold.triangles << 0, 1, 2, 1, 0, 3;
  const std::vector<std::pair<int, int>> both{{0, 1}};
  EXPECT_EQ(self_intersecting_triangles(fold), both);
  EXPECT_EQ(cgal_pairs(fold), both);
  Mesh open = fold, bent = fold;
  open.vertices(3, 1) = -0.8;  // the other side of the edge
  bent.vertices(3, 2) = 1e-9;  // out of the plane: they meet only along the edge
  for (const Mesh& m : {open, bent}) {
    EXPECT_TRUE(self_intersecting_triangles(m).empty());
    EXPECT_TRUE(cgal_pairs(m).empty());
  }
}

// Undoing the moves that cross: the noisy torus, moved back only where it crosses itself, is
// free of crossings by CGAL's test, and most moves are kept (MC's slivers make many crossings).
TEST(SelfIntersections, RevertOnlyTheCrossingMoves) {
  Mesh clean;
  Mesh mesh = noisy_mesh("torus", 32, 0.25, 3, &clean);
  const Mesh moved = mesh;
  const UntangleStats stats = revert_self_intersections(mesh, clean.vertices);
  EXPECT_TRUE(cgal_pairs(mesh).empty());
  EXPECT_EQ(stats.intersections_left, 0);
  EXPECT_EQ(stats.intersections_found, long(self_intersecting_triangles(moved).size()));
  int kept = 0, back = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    if (mesh.vertices.row(v) == moved.vertices.row(v)) ++kept;
    if (mesh.vertices.row(v) == clean.vertices.row(v)) ++back;
  }
  EXPECT_EQ(back, stats.vertices_reverted);
  EXPECT_EQ(kept + back, mesh.vertices.rows());
  EXPECT_GT(stats.intersections_found, 5);
  EXPECT_GT(kept, 2 * back);
  std::cout << stats.intersections_found << " crossing pairs, " << back << " of "
            << mesh.vertices.rows() << " vertices moved back\n";
  EXPECT_THROW(revert_self_intersections(mesh, clean.vertices.topRows(3)), Error);
}

// GCP's Poisson meshes of the shared meshes with the most crossings before they were undone
// (plane and wingnut at 32^3: 138 and 122 pairs, from the projection's and carving's moves) have
// none by CGAL's test, and neither have the local meshes (the default on grids).
TEST(SelfIntersections, GcpMeshesOfThinShapesDoNotCrossThemselves) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  for (const char* name : {"plane", "wingnut"}) {
    SCOPED_TRACE(name);
    const Grid grid = test::shared_mesh_grid(name, 32);
    ContourOptions poisson;
    poisson.reconstruction = Reconstruction::Poisson;
    const ContourResult r = contour(grid_input(grid), poisson);
    ASSERT_TRUE(r.fallback.empty()) << r.fallback;
    ASSERT_TRUE(r.untangling.has_value());
    std::cout << name << ": " << r.untangling->intersections_found << " crossing pairs, "
              << r.untangling->vertices_reverted << " vertices moved back\n";
    EXPECT_GT(r.untangling->intersections_found, 10);
    EXPECT_EQ(r.untangling->intersections_left, 0);
    EXPECT_TRUE(cgal_pairs(*r.mesh).empty());
    const ContourResult local = contour(grid_input(grid), ContourOptions{});
    ASSERT_TRUE(local.fallback.empty()) << local.fallback;
    EXPECT_EQ(local.reconstruction, Reconstruction::Local);
    EXPECT_TRUE(cgal_pairs(*local.mesh).empty());
  }
}
