// sdfcontour.h's calls (a grid, a function, scattered samples, a .vdb) against the surfaces they
// were sampled from and the pipeline's own properties.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/sdfcontour.h"

namespace sdfcontour {
namespace {

constexpr int kN = 32;
constexpr double kRadius = 0.55;

// A sphere's distances on [-1, 1]^3, plus `offset`.
template <class T>
std::vector<T> sphere_values(double offset = 0) {
  std::vector<T> v(std::size_t(kN) * kN * kN);
  const double h = 2.0 / (kN - 1);
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j)
      for (int k = 0; k < kN; ++k)
        v[(std::size_t(i) * kN + j) * kN + k] = T(
            std::sqrt(std::pow(-1 + i * h, 2) + std::pow(-1 + j * h, 2) + std::pow(-1 + k * h, 2)) -
            kRadius + offset);
  return v;
}

double worst_off_sphere(const Mesh& mesh) {
  double worst = 0;
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    worst = std::max(worst, std::abs(mesh.vertices.row(v).norm() - kRadius));
  return worst;
}

TEST(ContourGrid, GcpIsCloserToTheSphereThanMarchingCubesAndClosed) {
  const auto values = sphere_values<double>();
  const Mesh gcp = contour_grid(values.data(), {kN, kN, kN}, Bounds{});
  GridSettings mc_settings;
  mc_settings.method = "mc";
  const Mesh mc = contour_grid(values.data(), {kN, kN, kN}, Bounds{}, 0, mc_settings);
  const double h = 2.0 / (kN - 1);
  EXPECT_LT(worst_off_sphere(gcp), worst_off_sphere(mc));
  EXPECT_LT(worst_off_sphere(gcp), 0.02 * h);
  const MeshTopology topology = mesh_topology(gcp);
  EXPECT_TRUE(topology.closed && topology.consistently_oriented);
  EXPECT_EQ(topology.nonmanifold_edges, 0);
  EXPECT_EQ(topology.euler_characteristic, 2);
}

TEST(ContourGrid, TheIsovalueContoursTheShiftedLevelAndFloatsAgreeWithDoubles) {
  // The level 0.1 of (distance + 0.1) is the same sphere; the isovalue is subtracted in the
  // values' own precision.
  const auto shifted = sphere_values<double>(0.1);
  GridSettings mc;
  mc.method = "mc";
  const Mesh a = contour_grid(shifted.data(), {kN, kN, kN}, Bounds{}, 0.1, mc);
  const auto plain = sphere_values<double>();
  const Mesh b = contour_grid(plain.data(), {kN, kN, kN}, Bounds{}, 0.0, mc);
  ASSERT_EQ(a.triangles.rows(), b.triangles.rows());
  EXPECT_LT((a.vertices - b.vertices).cwiseAbs().maxCoeff(), 1e-9);
  const auto floats = sphere_values<float>();
  const Mesh c = contour_grid(floats.data(), {kN, kN, kN}, Bounds{});
  EXPECT_LT(worst_off_sphere(c), 0.05 * 2.0 / (kN - 1));  // float32 rounding of the distances
}

TEST(ContourGrid, BadInputIsAnErrorWithOneLine) {
  auto values = sphere_values<double>();
  auto throws = [&](auto&& call) {
    try {
      call();
    } catch (const Error& e) {
      return std::string(e.what()).find('\n') == std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(throws([&] { contour_grid(values.data(), {kN, kN, 1}, Bounds{}); }));
  EXPECT_TRUE(throws([&] { contour_grid(values.data(), {kN, kN, kN}, Bounds{}, 5.0); }));
  EXPECT_TRUE(throws([&] { contour_grid(values.data(), {kN, kN, kN}, Bounds{}, NAN); }));
  GridSettings unknown;
  unknown.method = "gtcp";
  EXPECT_TRUE(throws([&] { contour_grid(values.data(), {kN, kN, kN}, Bounds{}, 0, unknown); }));
  unknown.method = "dual";
  EXPECT_TRUE(throws([&] { contour_grid(values.data(), {kN, kN, kN}, Bounds{}, 0, unknown); }));
  values[7] = NAN;
  EXPECT_TRUE(throws([&] { contour_grid(values.data(), {kN, kN, kN}, Bounds{}); }));
  EXPECT_TRUE(throws([&] {
    contour_grid(static_cast<const double*>(nullptr), {kN, kN, kN}, Bounds{});
  }));
}

// One line, and a sdfcontour::Error.
template <class Call>
bool one_line_error(Call&& call) {
  try {
    call();
  } catch (const Error& e) {
    return std::string(e.what()).find('\n') == std::string::npos;
  }
  return false;
}

double sphere_distance(const Eigen::Vector3d& p) {
  return p.norm() - kRadius;
}

TEST(ContourFunction, IsContourGridOfTheSampledFunction) {
  // The same samples, so the same mesh bit for bit; the function is called from every thread.
  const auto values = sphere_values<double>();
  const Mesh from_grid = contour_grid(values.data(), {kN, kN, kN}, Bounds{});
  const Mesh from_function = contour_function(sphere_distance, {kN, kN, kN}, Bounds{});
  ASSERT_EQ(from_function.triangles, from_grid.triangles);
  EXPECT_EQ(from_function.vertices, from_grid.vertices);
  EXPECT_LT(worst_off_sphere(from_function), 0.02 * 2.0 / (kN - 1));
}

TEST(ContourFunction, ANonFiniteValueOrNoFunctionIsAnError) {
  const auto hole = [](const Eigen::Vector3d& p) {
    return p.norm() < 0.1 ? std::nan("") : p.norm() - kRadius;
  };
  EXPECT_TRUE(one_line_error([&] { contour_function(hole, {kN, kN, kN}, Bounds{}); }));
  EXPECT_TRUE(one_line_error([] { contour_function(nullptr, {kN, kN, kN}, Bounds{}); }));
  EXPECT_TRUE(one_line_error([] { contour_function(sphere_distance, {kN, 1, kN}, Bounds{}); }));
}

// n uniform random samples of the sphere's distance in [-1, 1]^3.
Samples random_sphere_samples(int n) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  Samples s;
  s.points.resize(n, 3);
  s.values.resize(n);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) s.points(i, a) = coordinate(random);
    s.values[i] = sphere_distance(s.points.row(i).transpose());
  }
  return s;
}

TEST(ContourSamples, ScatteredSamplesGiveTheSphereClosed) {
  const Samples s = random_sphere_samples(6000);
  const double spacing = 2.0 / std::cbrt(6000.0);  // the samples' mean spacing
  SampleSettings mt;
  mt.method = "mt-dt";
  const Mesh mt_mesh = contour_samples(s.points, s.values, mt);
  const Mesh gcp = contour_samples(s.points, s.values);
  // Marching tetrahedra interpolates each crossing linearly along an edge; GCP's Poisson mesh
  // follows the contact points, which lie on the sphere.
  for (const Mesh* m : {&mt_mesh, &gcp}) {
    ASSERT_GT(m->triangles.rows(), 100);
    EXPECT_LT(worst_off_sphere(*m), 0.25 * spacing);
    const MeshTopology topology = mesh_topology(*m);
    EXPECT_TRUE(topology.closed);
    EXPECT_EQ(topology.euler_characteristic, 2);
  }
}

TEST(ContourSamples, BadInputIsAnErrorWithOneLine) {
  Samples s = random_sphere_samples(500);
  const Eigen::VectorXd fewer = s.values.head(400);
  EXPECT_TRUE(one_line_error([&] { contour_samples(s.points, fewer); }));
  SampleSettings mc;
  mc.method = "mc";
  EXPECT_TRUE(one_line_error([&] { contour_samples(s.points, s.values, mc); }));
  SampleSettings deep;
  deep.depth = 40;
  EXPECT_TRUE(one_line_error([&] { contour_samples(s.points, s.values, deep); }));
  const Eigen::VectorXd outside = s.values.cwiseAbs();
  EXPECT_TRUE(one_line_error([&] { contour_samples(s.points, outside); }));
  s.values[3] = NAN;
  EXPECT_TRUE(one_line_error([&] { contour_samples(s.points, s.values); }));
}

// The exact distance to the box in tests/data/rotated_box.vdb (data/make_rotated_box.cpp), in
// the world: centre (0.15, 0.05, 0.25), half sides (0.3, 0.2, 0.12).
double rotated_box_distance(const Eigen::Vector3d& p) {
  const Eigen::Vector3d q =
      (p - Eigen::Vector3d(0.15, 0.05, 0.25)).cwiseAbs() - Eigen::Vector3d(0.3, 0.2, 0.12);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

TEST(ContourVdb, TheLevelSetComesOutWhereItsTransformPutsItOnEveryMethod) {
  const std::string vdb = std::string(SDFCONTOUR_SOURCE_DIR) + "/tests/data/rotated_box.vdb";
  const double voxel = 0.05;
  for (const char* method : {"gcp", "mc", "mt-rt"}) {
    GridSettings settings;
    settings.method = method;
    const Mesh mesh = contour_vdb(vdb, settings);
    ASSERT_GT(mesh.triangles.rows(), 100) << method;
    double sum = 0, worst = 0;
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
      const double d = std::abs(rotated_box_distance(mesh.vertices.row(v).transpose()));
      sum += d;
      worst = std::max(worst, d);
    }
    EXPECT_LT(sum / double(mesh.vertices.rows()), 0.1 * voxel) << method;
    EXPECT_LT(worst, 0.6 * voxel) << method;
    EXPECT_TRUE(mesh_topology(mesh).closed) << method;
  }
  EXPECT_THROW(contour_vdb(vdb + ".missing"), Error);
  GridSettings gcp;
  EXPECT_TRUE(one_line_error([&] { contour_vdb(vdb, gcp, "density"); }));
}

}  // namespace
}  // namespace sdfcontour
