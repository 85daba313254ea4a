#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/pipeline/pipeline.h"

using namespace sdfcontour;

namespace {

// Edges used by one triangle only.
std::vector<std::pair<int, int>> boundary_edges(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> uses;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) {
      const int a = mesh.triangles(t, c), b = mesh.triangles(t, (c + 1) % 3);
      ++uses[std::minmax(a, b)];
    }
  std::vector<std::pair<int, int>> out;
  for (const auto& [edge, n] : uses)
    if (n == 1) out.push_back(edge);
  return out;
}

}  // namespace

// A sphere of radius 0.6 cut at x = 0.3: every vertex on the kept side, the cut's boundary
// exactly on the plane and nowhere else, one piece, and the area of the sphere less the cap.
TEST(Clipping, CutsAMeshAlongTheBoxSide) {
  const Grid grid = sample_grid(*make_builtin_shape("sphere"), 48, Bounds{});
  const Mesh sphere = marching_cubes(grid);
  const double r = 0.6;  // the builtin sphere's radius, checked against the mesh
  EXPECT_NEAR(sphere.vertices.rowwise().norm().maxCoeff(), r, 0.01);
  const Eigen::Vector3d lo = Eigen::Vector3d::Constant(-1), hi(0.3, 1, 1);
  Mesh cut = sphere;
  EXPECT_TRUE(clip_mesh_to_box(cut, lo, hi));
  EXPECT_LE(cut.vertices.col(0).maxCoeff(), 0.3);
  const auto boundary = boundary_edges(cut);
  ASSERT_FALSE(boundary.empty());
  for (const auto& [a, b] : boundary) {
    EXPECT_EQ(cut.vertices(a, 0), 0.3);
    EXPECT_EQ(cut.vertices(b, 0), 0.3);
  }
  EXPECT_EQ(connected_components(cut), 1);
  const double kept = 4 * M_PI * r * r - 2 * M_PI * r * (r - 0.3);
  EXPECT_NEAR(surface_area(cut) / kept, surface_area(sphere) / (4 * M_PI * r * r), 1e-3);
  EXPECT_TRUE(mesh_topology(cut).consistently_oriented);
  // A box holding the mesh leaves it as it was.
  Mesh same = sphere;
  EXPECT_FALSE(clip_mesh_to_box(same, lo, Eigen::Vector3d::Constant(1)));
  EXPECT_EQ(same.vertices, sphere.vertices);
  EXPECT_EQ(same.triangles, sphere.triangles);
  // A box missing it leaves nothing.
  Mesh none = sphere;
  EXPECT_TRUE(clip_mesh_to_box(none, Eigen::Vector3d::Constant(0.9), hi.cwiseMax(1.0)));
  EXPECT_EQ(none.triangles.rows(), 0);
}

// GCP on a grid that cuts the surface (as a cropped scan's TSDF does) keeps GCP's accuracy inside
// the grid instead of falling back to marching cubes: the reconstruction closes the surface
// outside, and that part is cut away.
TEST(Clipping, GcpOnAGridThatCutsTheSurface) {
  Bounds bounds;
  bounds.max.x() = 0.3;
  const auto shape = make_builtin_shape("sphere");
  const Grid grid = sample_grid(*shape, 48, bounds);
  const double h = grid.spacing().maxCoeff();
  ContourOptions options;
  options.method = Method::Gcp;
  options.reconstruction = Reconstruction::Poisson;  // (the local mesh stops at the grid's sides)
  const ContourResult r = contour(grid_input(grid), options);
  ASSERT_TRUE(r.fallback.empty()) << r.fallback;
  EXPECT_TRUE(r.clipped_to_grid);
  ASSERT_TRUE(r.mesh);
  EXPECT_LE(r.mesh->vertices.col(0).maxCoeff(), 0.3);
  EXPECT_EQ(connected_components(*r.mesh), 1);
  double gcp_worst = 0, mc_worst = 0;
  for (Eigen::Index v = 0; v < r.mesh->vertices.rows(); ++v)
    gcp_worst = std::max(gcp_worst, std::abs(r.mesh->vertices.row(v).norm() - 0.6));
  const Mesh mc = marching_cubes(grid);
  for (Eigen::Index v = 0; v < mc.vertices.rows(); ++v)
    mc_worst = std::max(mc_worst, std::abs(mc.vertices.row(v).norm() - 0.6));
  std::cout << "largest distance to the sphere: gcp " << gcp_worst / h << " h, mc " << mc_worst / h
            << " h\n";
  EXPECT_LT(gcp_worst, mc_worst);
  // The local mesh (the default on grids) stops at the grid's side, inside the grid's box.
  const ContourResult local = contour(grid_input(grid), ContourOptions{});
  ASSERT_TRUE(local.fallback.empty()) << local.fallback;
  EXPECT_EQ(local.reconstruction, Reconstruction::Local);
  EXPECT_LE(local.mesh->vertices.col(0).maxCoeff(), 0.3);
  double local_worst = 0;
  for (Eigen::Index v = 0; v < local.mesh->vertices.rows(); ++v)
    local_worst = std::max(local_worst, std::abs(local.mesh->vertices.row(v).norm() - 0.6));
  EXPECT_LT(local_worst, mc_worst);
}

// A plane through the whole grid (a terrain, a wall): the grid's sides are inside in part, so
// the reconstruction keeps Neumann boundaries rather than forcing the far field outside (which
// wrapped the inside half in a closed sheet: half the vertices off the plane, then marching
// cubes by fallback). GCP is exact on a linear field, so the mesh lies on the plane.
TEST(Clipping, GcpOnAPlaneThroughTheGrid) {
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
  Grid grid;
  grid.dims = {32, 32, 32};
  grid.values.resize(32 * 32 * 32);
  for (int i = 0; i < 32; ++i)
    for (int j = 0; j < 32; ++j)
      for (int k = 0; k < 32; ++k) {
        const Eigen::Vector3d p =
            grid.bounds.min + grid.spacing().cwiseProduct(Eigen::Vector3d(i, j, k));
        grid.values[Eigen::Index(grid.index(i, j, k))] = n.dot(p) - 0.1;
      }
  const double h = grid.spacing().maxCoeff();
  ContourOptions poisson;  // (the local mesh stops at the grid's sides)
  poisson.reconstruction = Reconstruction::Poisson;
  const ContourResult r = contour(grid_input(grid), poisson);
  ASSERT_TRUE(r.fallback.empty()) << r.fallback;
  EXPECT_TRUE(r.clipped_to_grid);
  ASSERT_TRUE(r.mesh);
  EXPECT_EQ(connected_components(*r.mesh), 1);
  double worst = 0;
  for (Eigen::Index v = 0; v < r.mesh->vertices.rows(); ++v)
    worst = std::max(worst, std::abs(n.dot(r.mesh->vertices.row(v).transpose()) - 0.1));
  EXPECT_LT(worst, 1e-3 * h);
  // It spans the grid: its area is the plane's inside the box, to a few percent (the cut's
  // edges follow the box's sides exactly).
  EXPECT_GT(surface_area(*r.mesh), 4.0 * 0.9 / n.z());
  // The local mesh (the default on grids) lies on the plane too, up to the grid's sides.
  const ContourResult local = contour(grid_input(grid), ContourOptions{});
  ASSERT_TRUE(local.fallback.empty()) << local.fallback;
  EXPECT_EQ(local.reconstruction, Reconstruction::Local);
  EXPECT_EQ(connected_components(*local.mesh), 1);
  double local_worst = 0;
  for (Eigen::Index v = 0; v < local.mesh->vertices.rows(); ++v)
    local_worst =
        std::max(local_worst, std::abs(n.dot(local.mesh->vertices.row(v).transpose()) - 0.1));
  EXPECT_LT(local_worst, 1e-3 * h);
}
