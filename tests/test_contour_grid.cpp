// sdfcontour.h's contour_grid: the one-call entry point against the pipeline's own properties.
#include <gtest/gtest.h>

#include <cmath>
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

}  // namespace
}  // namespace sdfcontour
