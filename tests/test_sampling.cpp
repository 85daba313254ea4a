#include <fstream>

#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"
#include "test_support.h"

using namespace sdfcontour;
using Eigen::Vector3d;

namespace {

const std::string kMeshes = SDFCONTOUR_SHARED_DIR "/data/meshes/";

// The shared sphere (radius 1) and torus (radii 1 and 0.25 about y) after normalisation to
// [-0.9, 0.9]: radius 0.9; radii 0.72 and 0.18.
double exact_sphere(const Vector3d& p) {
  return p.norm() - 0.9;
}
double exact_torus(const Vector3d& p) {
  return std::hypot(std::hypot(p.x(), p.z()) - 0.72, p.y()) - 0.18;
}

// Points on the exact torus and sphere, for the Hausdorff distance between mesh and surface.
PointMatrix exact_surface_points(bool torus, int count) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 2 * M_PI);
  std::normal_distribution<double> g;
  PointMatrix p(count, 3);
  for (int i = 0; i < count; ++i) {
    if (torus) {
      const double s = u(rng), t = u(rng);
      p.row(i) << (0.72 + 0.18 * std::cos(t)) * std::cos(s), 0.18 * std::sin(t),
          (0.72 + 0.18 * std::cos(t)) * std::sin(s);
    } else {
      p.row(i) = 0.9 * Vector3d(g(rng), g(rng), g(rng)).normalized().transpose();
    }
  }
  return p;
}

}  // namespace

// Distance functions of two surfaces differ by at most their Hausdorff distance, and their signs
// agree away from the surfaces: the mesh SDF must match the analytic SDF that well.
TEST(Sampling, MeshSdfMatchesAnalyticShapes) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  for (const bool torus : {false, true}) {
    SCOPED_TRACE(torus ? "torus" : "sphere");
    const Mesh mesh =
        normalize_mesh(read_mesh(kMeshes + (torus ? "torus.obj" : "sphere.obj")), 0.9);
    const MeshSdf sdf(mesh);
    auto exact = torus ? exact_torus : exact_sphere;
    // Hausdorff distance between the mesh and the exact surface.
    PointMatrix on_mesh(mesh.vertices.rows() + 50000, 3);
    on_mesh << mesh.vertices, sample_surface(mesh, 50000, 2);
    double hausdorff = 0;
    for (Eigen::Index i = 0; i < on_mesh.rows(); ++i)
      hausdorff = std::max(hausdorff, std::abs(exact(on_mesh.row(i).transpose())));
    hausdorff = std::max(hausdorff,
                         point_mesh_distances(exact_surface_points(torus, 50000), mesh).maxCoeff());
    std::cout << (torus ? "torus" : "sphere") << " mesh vs exact surface: Hausdorff " << hausdorff
              << "\n";
    const Samples s = sample_grid(sdf, 32, Bounds{}).to_samples();
    double worst = 0;
    for (Eigen::Index i = 0; i < s.points.rows(); ++i)
      worst = std::max(worst, std::abs(s.values[i] - exact(s.points.row(i).transpose())));
    EXPECT_LE(worst, 1.02 * hausdorff + 1e-12);
    EXPECT_LT(hausdorff, 0.01);  // the meshes are fine enough for the check to mean something
    // Gradients are unit vectors pointing away from the closest point.
    for (Eigen::Index i = 0; i < s.points.rows(); i += 97) {
      const Vector3d p = s.points.row(i).transpose();
      EXPECT_NEAR(sdf.gradient(p).norm(), 1.0, 1e-9);
      EXPECT_LT(std::abs(sdf.distance(sdf.closest_point(p))), 1e-9);
    }
  }
}

TEST(Sampling, NormalisationSpansTheBox) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  const Mesh m = normalize_mesh(read_mesh(kMeshes + "bunny.obj"), 0.9);
  const Eigen::RowVector3d lo = m.vertices.colwise().minCoeff(),
                           hi = m.vertices.colwise().maxCoeff();
  EXPECT_NEAR((hi - lo).maxCoeff(), 1.8, 1e-12);
  EXPECT_LT((lo + hi).norm(), 1e-12);
}

// Cube [-1,1]^3 against the same cube shifted by t along x. Directed distances, integrated over
// the 24 units of area: face x=-1 gives 4t; face x=+1, inside the other cube, gives
// 4 [1 - (1-t)^3] / 3; the four side faces give 4 t^2. Squared: 4t^2, 8 (t^2/2 - 2t^3/3 + t^4/4)
// and 8 t^3 / 3. The Hausdorff distance is t. Both directions are alike by symmetry.
TEST(Metrics, CubeAgainstShiftedCube) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  const Mesh cube = normalize_mesh(read_mesh(kMeshes + "cube.obj"), 1.0);
  Mesh shifted = cube;
  const double t = 0.3;
  shifted.vertices.col(0).array() += t;
  const SurfaceDistances d = surface_distances(cube, shifted, 400000, 5);
  const double mean = (4 * t + 4 * (1 - std::pow(1 - t, 3)) / 3 + 4 * t * t) / 24;
  const double rms = std::sqrt(
      (4 * t * t + 8 * (t * t / 2 - 2 * t * t * t / 3 + std::pow(t, 4) / 4) + 8 * t * t * t / 3) /
      24);
  std::cout << "cube: L1 " << d.l1 << " (exact " << mean << "), L2 " << d.l2 << " (exact " << rms
            << "), Linf " << d.hausdorff << "\n";
  EXPECT_NEAR(d.hausdorff, t, 1e-9);
  EXPECT_NEAR(d.l1, mean, 0.01 * mean);
  EXPECT_NEAR(d.l2, rms, 0.01 * rms);
  EXPECT_NEAR(d.mean_ab, d.mean_ba, 0.01 * mean);
}

// A sphere against the same sphere scaled by 1.1 about its centre: every point is 0.1 r from the
// other surface, up to the meshes' faceting.
TEST(Metrics, SphereAgainstScaledSphere) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  const Mesh sphere = read_mesh(kMeshes + "sphere.obj");
  Mesh scaled = sphere;
  scaled.vertices *= 1.1;
  const SurfaceDistances d = surface_distances(sphere, scaled, 100000, 7);
  for (double v : {d.hausdorff, d.l1, d.l2}) EXPECT_NEAR(v, 0.1, 0.012);
  EXPECT_LE(d.l1, d.l2 + 1e-12);
  EXPECT_LE(d.l2, d.hausdorff + 1e-12);
}

TEST(Metrics, ComponentsAndGenus) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  const Mesh torus = read_mesh(kMeshes + "torus.obj");
  const MeshTopology t = mesh_topology(torus);
  EXPECT_TRUE(t.closed);
  EXPECT_EQ(connected_components(torus), 1);
  EXPECT_EQ(t.euler_characteristic, 0);  // genus 1
  Mesh two = torus;
  two.vertices.conservativeResize(2 * torus.vertices.rows(), 3);
  two.vertices.bottomRows(torus.vertices.rows()) =
      torus.vertices.rowwise() + Eigen::RowVector3d(5, 0, 0);
  two.triangles.conservativeResize(2 * torus.triangles.rows(), 3);
  two.triangles.bottomRows(torus.triangles.rows()) =
      torus.triangles.array() + int(torus.vertices.rows());
  EXPECT_EQ(connected_components(two), 2);
}

TEST(Sampling, RejectsBadMeshes) {
  SDFCONTOUR_REQUIRE_PATH(kMeshes, "the shared test meshes");
  Mesh open = read_mesh(kMeshes + "cube.obj");
  open.triangles.conservativeResize(open.triangles.rows() - 1, 3);
  EXPECT_THROW(MeshSdf{open}, Error);
  EXPECT_THROW(MeshSdf{Mesh{}}, Error);
  EXPECT_THROW(read_mesh("/nonexistent/mesh.obj"), Error);
  const auto dir = test::temp_dir("bad_mesh");
  std::ofstream((dir / "junk.obj").string()) << "this is not a mesh\n";
  EXPECT_THROW(read_mesh((dir / "junk.obj").string()), Error);
  std::ofstream((dir / "empty.off").string()) << "OFF\n0 0 0\n";
  EXPECT_THROW(read_mesh((dir / "empty.off").string()), Error);
}
