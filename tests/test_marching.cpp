#include <cmath>
#include <cstdlib>

#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/io/npy.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

struct Expected {
  std::string name;
  double volume;  // analytic enclosed volume
  long euler;     // 2 * components - 2 * genus
};

std::vector<Expected> shapes() {
  const double pi = M_PI;
  return {
      {"sphere", 4.0 / 3.0 * pi * 0.6 * 0.6 * 0.6, 2},
      {"torus", 2 * pi * pi * 0.55 * 0.25 * 0.25, 0},
      {"box", 8 * 0.6 * 0.45 * 0.35, 2},
      {"plate", 8 * 0.7 * 0.5 * 0.06, 2},
      {"shell", 4.0 / 3.0 * pi * (0.65 * 0.65 * 0.65 - 0.55 * 0.55 * 0.55), 4},
      {"csg", -1, 2},
  };
}

void expect_closed_outward(const Mesh& m, const Expected& e, double volume_tolerance) {
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(t.closed) << t.boundary_edges << " boundary, " << t.nonmanifold_edges
                        << " non-manifold edges";
  EXPECT_TRUE(t.consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, e.euler);
  const double v = signed_volume(m);
  EXPECT_GT(v, 0) << "not outward oriented";
  if (e.volume > 0) {
    EXPECT_NEAR(v / e.volume, 1.0, volume_tolerance);
  }
}

}  // namespace

TEST(Marching, TetrahedraOnGridsAreClosedAndOutward) {
  for (const Expected& e : shapes()) {
    const auto shape = make_builtin_shape(e.name);
    const Samples s = sample_grid(*shape, 40, Bounds{}).to_samples();
    for (auto kind : {TriangulationKind::Regular, TriangulationKind::Delaunay}) {
      SCOPED_TRACE(e.name + (kind == TriangulationKind::Regular ? " mt-rt" : " mt-dt"));
      const Triangulation tri = triangulate(s.points, s.values, {kind, true});
      expect_closed_outward(marching_tetrahedra(s.points, s.values, tri.tets), e, 0.05);
    }
  }
}

TEST(Marching, TetrahedraOnRandomSamplesAreClosedAndOutward) {
  for (const std::string name : {"sphere", "torus", "csg"}) {
    SCOPED_TRACE(name);
    const auto shape = make_builtin_shape(name);
    const Samples s = sample_random(*shape, 30000, Bounds{}, 3);
    const Triangulation tri = triangulate(s.points, s.values, {TriangulationKind::Delaunay, true});
    const Mesh m = marching_tetrahedra(s.points, s.values, tri.tets);
    for (const Expected& e : shapes())
      if (e.name == name) expect_closed_outward(m, e, 0.1);
  }
}

TEST(Marching, CubesAreClosedAndOutward) {
  for (const Expected& e : shapes()) {
    SCOPED_TRACE(e.name);
    const auto shape = make_builtin_shape(e.name);
    expect_closed_outward(marching_cubes(sample_grid(*shape, 40, Bounds{})), e, 0.05);
  }
}

TEST(Marching, CubesHandleEveryCornerConfiguration) {
  // A 2x2x2 grid for each of the 254 mixed sign patterns, inside a padded 4x4x4 grid of
  // positive values so that each pattern's surface must close.
  for (int mask = 1; mask < 255; ++mask) {
    const Mesh m = marching_cubes(test::single_cube_grid(mask));
    const MeshTopology t = mesh_topology(m);
    EXPECT_TRUE(t.closed && t.consistently_oriented) << "mask " << mask;
    EXPECT_GT(signed_volume(m), 0) << "mask " << mask;
  }
}

TEST(Marching, CubesAgreeWithScikitImage) {
  SDFCONTOUR_REQUIRE_PYTHON_MODULE("skimage");
  const auto dir = test::temp_dir("mc_skimage");
  for (const std::string name : {"sphere", "torus", "csg", "box"}) {
    for (int n : {24, 48}) {
      SCOPED_TRACE(name + " " + std::to_string(n));
      const auto shape = make_builtin_shape(name);
      const Grid g = sample_grid(*shape, n, Bounds{});
      const std::string grid_path = (dir / "grid.npy").string(), verts = (dir / "v.npy").string(),
                        faces = (dir / "f.npy").string();
      write_npy(grid_path, {std::size_t(n), std::size_t(n), std::size_t(n)},
                std::vector<double>(g.values.data(), g.values.data() + g.values.size()));
      const double h = g.spacing()[0];
      const std::string cmd = "/usr/bin/python3 " SDFCONTOUR_SOURCE_DIR "/tests/skimage_mc.py " +
                              grid_path + " " + std::to_string(h) + " -1 " + verts + " " + faces;
      ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
      const NpyArray v = read_npy(verts), f = read_npy(faces);
      Mesh reference;
      reference.vertices =
          Eigen::Map<const PointMatrix>(v.data.data(), Eigen::Index(v.shape[0]), 3);
      reference.triangles = Eigen::Map<const Eigen::Matrix<double, -1, 3, Eigen::RowMajor>>(
                                f.data.data(), Eigen::Index(f.shape[0]), 3)
                                .cast<int>();
      const Mesh ours = marching_cubes(g);
      // Both put one vertex on every sign-changing edge by linear interpolation and split the
      // same polygons, so the vertex sets and face counts match.
      EXPECT_EQ(ours.vertices.rows(), reference.vertices.rows());
      EXPECT_EQ(ours.triangles.rows(), reference.triangles.rows());
      const double vertex_hausdorff =
          std::max(point_mesh_distances(ours.vertices, reference).maxCoeff(),
                   point_mesh_distances(reference.vertices, ours).maxCoeff());
      EXPECT_LT(vertex_hausdorff, 0.01 * h);
      const double area_ratio = surface_area(ours) / surface_area(reference);
      EXPECT_NEAR(area_ratio, 1.0, 0.005);
      // Lewiner's table splits some polygons along other diagonals than ours; the surfaces then
      // part by a fraction of a cell (the sagitta of the chord), never more than half a cell.
      // VTK's marching cubes parts from Lewiner's by as much (bench/mc_agreement.py).
      const double hausdorff = hausdorff_distance(ours, reference, 200000);
      EXPECT_LT(hausdorff, 0.5 * h);
      // And our splits are no less accurate: mean distance to the exact surface.
      auto mean_error = [&](const Mesh& m) {
        const PointMatrix p = sample_surface(m, 100000, 2);
        double sum = 0;
        for (Eigen::Index i = 0; i < p.rows(); ++i)
          sum += std::abs(shape->distance(p.row(i).transpose()));
        return sum / double(p.rows());
      };
      const double ours_error = mean_error(ours), reference_error = mean_error(reference);
      EXPECT_LT(ours_error, 1.02 * reference_error);
      std::cout << name << " " << n << "^3: vertex Hausdorff " << vertex_hausdorff / h
                << " h, area ratio " << area_ratio << ", surface Hausdorff " << hausdorff / h
                << " h, mean error to exact surface " << ours_error / h << " h (scikit-image "
                << reference_error / h << " h)\n";
    }
  }
}
