#include <tbb/global_control.h>

#include <cmath>

#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/poisson.h"
#include "test_support.h"

using namespace sdfcontour;
using Eigen::Vector3d;

namespace {

// Evenly spread exact samples: a Fibonacci sphere (radius 0.6) and a (u, v) grid on the torus
// (radii 0.55, 0.25), with their exact outward normals.
OrientedPoints even_points(const std::string& name, int count) {
  OrientedPoints o;
  std::vector<Vector3d> p, n;
  if (name == "sphere") {
    for (int i = 0; i < count; ++i) {
      const double z = 1 - (2.0 * i + 1) / count, r = std::sqrt(1 - z * z),
                   phi = i * M_PI * (3 - std::sqrt(5.0));
      n.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
      p.push_back(0.6 * n.back());
    }
  } else {
    const int nu = int(std::sqrt(count * 0.55 / 0.25)), nv = count / nu;
    for (int a = 0; a < nu; ++a)
      for (int b = 0; b < nv; ++b) {
        const double s = 2 * M_PI * (a + 0.5) / nu, t = 2 * M_PI * (b + 0.5) / nv;
        n.emplace_back(std::cos(t) * std::cos(s), std::cos(t) * std::sin(s), std::sin(t));
        p.push_back(Vector3d(0.55 * std::cos(s), 0.55 * std::sin(s), 0) + 0.25 * n.back());
      }
  }
  o.points.resize(Eigen::Index(p.size()), 3);
  o.normals.resize(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) {
    o.points.row(Eigen::Index(i)) = p[i].transpose();
    o.normals.row(Eigen::Index(i)) = n[i].transpose();
  }
  return o;
}

struct Error3 {
  double mean, max;
};

// |phi| of the exact shape over area-uniform samples of the mesh.
Error3 surface_error(const Mesh& m, const AnalyticShape& shape) {
  const PointMatrix p = sample_surface(m, 100000, 3);
  double sum = 0, worst = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const double e = std::abs(shape.distance(p.row(i).transpose()));
    sum += e;
    worst = std::max(worst, e);
  }
  return {sum / double(p.rows()), worst};
}

void expect_watertight(const Mesh& m, long euler) {
  const MeshTopology t = mesh_topology(m);
  EXPECT_GT(m.triangles.rows(), 0);
  EXPECT_TRUE(t.closed) << t.boundary_edges << " boundary, " << t.nonmanifold_edges
                        << " non-manifold edges";
  EXPECT_TRUE(t.consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, euler);
  EXPECT_GT(signed_volume(m), 0);
}

// The cell width at depth d for points whose bounding cube has side `extent`.
double cell_width(double extent, int depth, double scale = 1.1) {
  return extent * scale / double(1 << depth);
}

}  // namespace

TEST(Poisson, ExactSphereAndTorusAtDepth8) {
  for (const std::string name : {"sphere", "torus"}) {
    SCOPED_TRACE(name);
    const auto shape = make_builtin_shape(name);
    const OrientedPoints points = even_points(name, 60000);
    const PoissonResult r = poisson_reconstruct(points, {});
    expect_watertight(r.mesh, name == "sphere" ? 2 : 0);
    const double h = cell_width(name == "sphere" ? 1.2 : 1.6, 8);
    const Error3 e = surface_error(r.mesh, *shape);
    std::cout << name << ": mean |phi| " << e.mean / h << " cells, max " << e.max / h
              << " cells, iso " << r.iso_value << "\n";
    EXPECT_LT(e.mean, 0.01 * h);  // the target: within 1% of a cell
    EXPECT_LT(e.max, 0.15 * h);
    EXPECT_NEAR(r.iso_value, 0.5, 0.05);
    ASSERT_EQ(r.vertex_density.size(), r.mesh.vertices.rows());
    // Density in samples per unit area: count / surface area.
    const double area = name == "sphere" ? 4 * M_PI * 0.36 : 4 * M_PI * M_PI * 0.55 * 0.25;
    EXPECT_NEAR(r.vertex_density.mean() * area / double(points.points.rows()), 1.0, 0.2);
  }
}

// A refinement dilated by one cell instead of two: the finest depth holds far fewer cells, and
// the sphere from dense points still comes back within 1% of a cell on average.
TEST(Poisson, OneCellOfDilationRefinesLessAndStaysAccurate) {
  const auto shape = make_builtin_shape("sphere");
  const OrientedPoints points = even_points("sphere", 60000);
  PoissonOptions o;
  const PoissonResult two = poisson_reconstruct(points, o);
  o.refine_dilation = 1;
  const PoissonResult one = poisson_reconstruct(points, o);
  ASSERT_EQ(one.levels.back().depth, 8);
  ASSERT_EQ(two.levels.back().depth, 8);
  EXPECT_LT(one.levels.back().cells, 0.8 * two.levels.back().cells);
  expect_watertight(one.mesh, 2);
  const double h = cell_width(1.2, 8);
  const Error3 e = surface_error(one.mesh, *shape);
  EXPECT_LT(e.mean, 0.01 * h);
  EXPECT_LT(e.max, 0.15 * h);
  for (int bad : {0, 5}) {
    o.refine_dilation = bad;
    EXPECT_THROW(poisson_reconstruct(points, o), Error);
  }
}

TEST(Poisson, ScreeningWeightsAndBoundaries) {
  const auto shape = make_builtin_shape("sphere");
  const OrientedPoints points = even_points("sphere", 20000);
  const double h = cell_width(1.2, 7);
  const std::pair<PoissonBoundary, const char*> boundaries[] = {
      {PoissonBoundary::Neumann, "neumann"},
      {PoissonBoundary::Dirichlet, "dirichlet"},
      {PoissonBoundary::Free, "free"}};
  double error_plain = 0, error_screened = 0;
  for (double alpha : {0.0, 10.0}) {
    Mesh neumann;
    for (const auto& [boundary, name] : boundaries) {
      SCOPED_TRACE("alpha " + std::to_string(alpha) + " " + name);
      PoissonOptions o;
      o.depth = 7;
      o.point_weight = alpha;
      o.boundary = boundary;
      const PoissonResult r = poisson_reconstruct(points, o);
      expect_watertight(r.mesh, 2);
      const Error3 e = surface_error(r.mesh, *shape);
      std::cout << "alpha " << alpha << " " << name << ": mean |phi| " << e.mean / h << " cells\n";
      EXPECT_LT(e.mean, 0.1 * h);
      if (boundary == PoissonBoundary::Neumann) {
        (alpha == 0 ? error_plain : error_screened) = e.mean;
        neumann = r.mesh;
      }
      // Degree-1 free and Neumann bases span the same space, so the minimiser is the same.
      if (boundary == PoissonBoundary::Free) {
        ASSERT_EQ(r.mesh.triangles.rows(), neumann.triangles.rows());
        ASSERT_EQ(r.mesh.vertices.rows(), neumann.vertices.rows());
        EXPECT_TRUE(r.mesh.triangles == neumann.triangles);
        EXPECT_TRUE(r.mesh.vertices == neumann.vertices);
      }
    }
  }
  EXPECT_LT(error_screened, error_plain);  // screening pulls the surface onto the samples
}

// Point weights: all ones give the unweighted mesh bit for bit; a second, biased copy of the
// sphere (radius 0.6 + 0.02) pulls the surface out, less when its points weigh 0.05.
TEST(Poisson, PointWeightsScaleEachPointsPull) {
  const auto shape = make_builtin_shape("sphere");
  const OrientedPoints exact = even_points("sphere", 8000);
  PoissonOptions o;
  o.depth = 7;
  OrientedPoints ones = exact;
  ones.weights = Eigen::VectorXd::Ones(exact.points.rows());
  const Mesh plain = poisson_reconstruct(exact, o).mesh,
             weighted = poisson_reconstruct(ones, o).mesh;
  EXPECT_TRUE(plain.vertices == weighted.vertices);
  EXPECT_TRUE(plain.triangles == weighted.triangles);

  OrientedPoints both;
  const Eigen::Index n = exact.points.rows();
  both.points.resize(2 * n, 3);
  both.normals.resize(2 * n, 3);
  both.points << exact.points, exact.points * (0.62 / 0.6);
  both.normals << exact.normals, exact.normals;
  // Signed mean offset of the mesh from the true sphere.
  auto offset = [&](const OrientedPoints& p) {
    const Mesh m = poisson_reconstruct(p, o).mesh;
    double sum = 0;
    for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
      sum += shape->distance(m.vertices.row(v).transpose());
    return sum / double(m.vertices.rows());
  };
  const double equal = offset(both);
  both.weights = Eigen::VectorXd::Ones(2 * n);
  both.weights.tail(n).setConstant(0.05);
  const double down = offset(both);
  std::cout << "mean offset: equal weights " << equal << ", light copy " << down << "\n";
  EXPECT_GT(equal, 0.007);       // about halfway between the two spheres
  EXPECT_LT(down, 0.4 * equal);  // the light copy pulls less
  EXPECT_GT(down, -0.002);

  both.weights[3] = 0;
  EXPECT_THROW(poisson_reconstruct(both, o), Error);
  both.weights.resize(5);
  EXPECT_THROW(poisson_reconstruct(both, o), Error);
}

TEST(Poisson, SameMeshWhateverTheThreadCount) {
  const OrientedPoints points = even_points("torus", 20000);
  PoissonOptions o;
  o.depth = 7;
  Mesh one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = poisson_reconstruct(points, o).mesh;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = poisson_reconstruct(points, o).mesh;
  }
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
}

TEST(Poisson, SparseAndTinyInputs) {
  // A few hundred points: coarse splats, the tree stays shallow, the mesh still closes.
  const OrientedPoints sparse = even_points("sphere", 300);
  expect_watertight(poisson_reconstruct(sparse, {}).mesh, 2);
  // One point, or several at one place: no surface, said as an error (not an empty mesh or a
  // speck of vertices at one spot).
  for (const int n : {1, 6}) {
    OrientedPoints same;
    same.points = PointMatrix::Constant(n, 3, 0.25);
    same.normals = PointMatrix::Zero(n, 3);
    same.normals.col(2).setOnes();
    EXPECT_THROW(poisson_reconstruct(same, {}), Error) << n;
  }
}

// A thin plate sampled from both sides: the normals nearly cancel in the splatted field, and with
// Neumann boundaries the far field can end up level with the iso-value, filling the domain with
// spurious sheets. The reconstruction must notice and pin the far field (Dirichlet).
TEST(Poisson, ThinPlateStaysInsideItsBox) {
  OrientedPoints o;
  const int side = 24;
  o.points.resize(2 * side * side, 3);
  o.normals.resize(2 * side * side, 3);
  for (int s = 0; s < 2; ++s)
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        const int r = (s * side + i) * side + j;
        o.points.row(r) << -0.5 + i / double(side - 1), -0.3 + 0.6 * j / double(side - 1),
            s ? 0.004 : -0.004;
        o.normals.row(r) << 0, 0, s ? 1 : -1;
      }
  const PoissonResult r = poisson_reconstruct(o, {});
  ASSERT_GT(r.mesh.vertices.rows(), 0);
  EXPECT_TRUE(mesh_topology(r.mesh).closed);
  // Nothing far from the plate: every vertex within a tenth of the plate's size of its box.
  const Eigen::RowVector3d lo = r.mesh.vertices.colwise().minCoeff(),
                           hi = r.mesh.vertices.colwise().maxCoeff();
  EXPECT_GT(lo.x(), -0.6);
  EXPECT_LT(hi.x(), 0.6);
  EXPECT_GT(lo.z(), -0.1);
  EXPECT_LT(hi.z(), 0.1);
  std::cout << "thin plate: boundary fallback " << r.boundary_fallback << ", z range " << lo.z()
            << " .. " << hi.z() << "\n";
}

TEST(Poisson, RejectsBadInput) {
  OrientedPoints empty;
  EXPECT_THROW(poisson_reconstruct(empty, {}), Error);
  OrientedPoints p = even_points("sphere", 100);
  p.points(5, 1) = std::nan("");
  EXPECT_THROW(poisson_reconstruct(p, {}), Error);
  p = even_points("sphere", 100);
  p.normals.row(7).setZero();
  EXPECT_THROW(poisson_reconstruct(p, {}), Error);
  p = even_points("sphere", 100);
  PoissonOptions o;
  o.point_weight = -1;
  EXPECT_THROW(poisson_reconstruct(p, o), Error);
}

// The paper's claim at low resolution: GCP's mesh is closer to the true surface than marching
// cubes' on a smooth shape, and GTCP's (exact contact points) closer still or about as close.
TEST(Poisson, GcpBeatsMarchingCubesOnSmoothShapes) {
  for (const std::string name : {"torus", "csg"}) {
    SCOPED_TRACE(name);
    const auto shape = make_builtin_shape(name);
    const SdfInput input = grid_input(sample_grid(*shape, 24, Bounds{}));
    const double h = grid_view_of(input)->spacing()[0];
    ContourOptions o;
    double error[3];
    const Method methods[3] = {Method::Mc, Method::Gcp, Method::Gtcp};
    for (int m = 0; m < 3; ++m) {
      o.method = methods[m];
      const Mesh mesh = *contour_with_exact_sdf(input, *shape, o).mesh;
      expect_watertight(mesh, name == "torus" ? 0 : 2);
      error[m] = surface_error(mesh, *shape).mean;
    }
    std::cout << name << " 24^3 mean |phi|: mc " << error[0] / h << " h, gcp " << error[1] / h
              << " h, gtcp " << error[2] / h << " h\n";
    EXPECT_LT(error[1], 0.7 * error[0]);
    EXPECT_LT(error[2], 0.7 * error[0]);
  }
}

// Points biased a fifth of a spacing into a torus leave the samples just inside it outside the
// mesh. The samples within two spacings (of a 40^3 grid), as sign constraints, bring the surface
// back: almost all end on their side, and the mesh is closer to the torus.
TEST(Poisson, SignConstraintsKeepSamplesOnTheirSide) {
  const auto shape = make_builtin_shape("torus");
  const Grid grid = sample_grid(*shape, 40, Bounds{});
  const double h = grid.spacing()[0];
  OrientedPoints points = even_points("torus", 6000);
  points.points -= 0.2 * h * points.normals;
  const Samples all = grid.to_samples();
  SignedSamples sides;
  std::vector<Eigen::Index> near;
  for (Eigen::Index i = 0; i < all.values.size(); ++i)
    if (std::abs(all.values[i]) <= 2 * h) near.push_back(i);
  sides.points.resize(Eigen::Index(near.size()), 3);
  sides.values.resize(Eigen::Index(near.size()));
  for (std::size_t q = 0; q < near.size(); ++q) {
    sides.points.row(Eigen::Index(q)) = all.points.row(near[q]);
    sides.values[Eigen::Index(q)] = all.values[near[q]];
  }
  auto wrong_side = [&](const Mesh& m) {
    const MeshSdf own(m);
    long wrong = 0;
    for (Eigen::Index q = 0; q < sides.values.size(); ++q)
      wrong += (own.distance(sides.points.row(q).transpose()) < 0) != (sides.values[q] < 0);
    return wrong;
  };
  PoissonOptions o;
  o.depth = 7;
  const PoissonResult free = poisson_reconstruct(points, o);
  SignConstraintOptions so;
  so.radius = 1.5 * h;
  const PoissonResult held = poisson_reconstruct(points, o, sides, so);
  const long before = wrong_side(free.mesh), after = wrong_side(held.mesh);
  std::cout << "samples on the wrong side: " << before << " -> " << after << " (chi disagreed at "
            << held.sign_violations << ")\n";
  EXPECT_GT(before, 200);
  EXPECT_EQ(held.sign_violations_left, 0);
  EXPECT_EQ(after, 0);
  expect_watertight(held.mesh, 0);
  EXPECT_LT(surface_error(held.mesh, *shape).mean, surface_error(free.mesh, *shape).mean);
}
