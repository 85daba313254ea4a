#include <cmath>

#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/metrics/metrics.h"
#include "test_support.h"

using namespace sdfcontour;
using Eigen::Vector3d;

namespace {

// Dense points on each shape's surface and an inside test, built from the shape's plain
// description rather than from its distance function.
struct Reference {
  PointMatrix surface;
  std::function<bool(const Vector3d&)> inside;
};

Vector3d random_direction(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Vector3d d(n(rng), n(rng), n(rng));
  return d.normalized();
}

Reference reference(const std::string& name) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const int count = 200000;
  Reference r;
  r.surface.resize(count, 3);
  if (name == "box") {
    const Vector3d b(0.6, 0.45, 0.35);
    const double area[3] = {b.y() * b.z(), b.x() * b.z(), b.x() * b.y()};
    for (int i = 0; i < count; ++i) {
      const double pick = u(rng) * (area[0] + area[1] + area[2]);
      const int axis = pick < area[0] ? 0 : pick < area[0] + area[1] ? 1 : 2;
      Vector3d p;
      for (int a = 0; a < 3; ++a) p[a] = (2 * u(rng) - 1) * b[a];
      p[axis] = u(rng) < 0.5 ? -b[axis] : b[axis];
      r.surface.row(i) = p.transpose();
    }
    r.inside = [b](const Vector3d& p) { return (p.cwiseAbs() - b).maxCoeff() < 0; };
  } else if (name == "torus") {
    for (int i = 0; i < count; ++i) {
      const double s = 2 * M_PI * u(rng), t = 2 * M_PI * u(rng);
      r.surface.row(i) << (0.55 + 0.25 * std::cos(t)) * std::cos(s),
          (0.55 + 0.25 * std::cos(t)) * std::sin(s), 0.25 * std::sin(t);
    }
    r.inside = [](const Vector3d& p) {
      return std::pow(std::hypot(p.x(), p.y()) - 0.55, 2) + p.z() * p.z() < 0.0625;
    };
  } else if (name == "csg") {
    const Vector3d c0(-0.3, -0.05, 0.02), c1(0.35, 0.1, -0.03);
    const double r0 = 0.5, r1 = 0.42;
    int i = 0;
    while (i < count) {
      const bool first = u(rng) < 0.6;
      const Vector3d p = first ? Vector3d(c0 + r0 * random_direction(rng))
                               : Vector3d(c1 + r1 * random_direction(rng));
      if (first ? (p - c1).norm() < r1 : (p - c0).norm() < r0)
        continue;  // buried in the other sphere
      r.surface.row(i++) = p.transpose();
    }
    r.inside = [=](const Vector3d& p) { return (p - c0).norm() < r0 || (p - c1).norm() < r1; };
  }
  return r;
}

}  // namespace

TEST(BuiltinShapes, DistancesAreExact) {
  for (const std::string name : {"box", "torus", "csg"}) {
    SCOPED_TRACE(name);
    const auto shape = make_builtin_shape(name);
    const Reference ref = reference(name);
    const PointMatrix queries = test::random_points(300, 3);
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      const Vector3d p = queries.row(q).transpose();
      const double d = shape->distance(p);
      const double nearest = (ref.surface.rowwise() - p.transpose()).rowwise().norm().minCoeff();
      // No surface point is nearer than |d|, and the dense samples come within their spacing.
      EXPECT_LE(std::abs(d), nearest + 1e-12);
      EXPECT_NEAR(std::abs(d), nearest, 0.01);
      EXPECT_EQ(d < 0, ref.inside(p));
      // The gradient is a unit vector, and it leads to a surface point at distance |d|.
      const Vector3d g = shape->gradient(p);
      EXPECT_NEAR(g.norm(), 1.0, 1e-12);
      EXPECT_LT(std::abs(shape->distance(shape->closest_point(p))), 1e-12);
    }
  }
}

TEST(BuiltinShapes, GradientMatchesFiniteDifferences) {
  for (const auto& name : builtin_shape_names()) {
    SCOPED_TRACE(name);
    const auto shape = make_builtin_shape(name);
    const PointMatrix queries = test::random_points(500, 11);
    int checked = 0;
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      const Vector3d p = queries.row(q).transpose();
      const double h = 1e-6;
      Vector3d fd;
      for (int a = 0; a < 3; ++a) {
        Vector3d e = Vector3d::Zero();
        e[a] = h;
        fd[a] = (shape->distance(p + e) - shape->distance(p - e)) / (2 * h);
      }
      if (std::abs(fd.norm() - 1) > 1e-4) continue;  // a kink (medial axis) lies within h
      EXPECT_LT((fd - shape->gradient(p)).norm(), 1e-4);
      ++checked;
    }
    EXPECT_GT(checked, 450);
  }
}

TEST(BuiltinShapes, SpecParsing) {
  const BuiltinSpec grid = parse_builtin_spec("builtin:torus@64");
  EXPECT_EQ(grid.name, "torus");
  EXPECT_FALSE(grid.random);
  EXPECT_EQ(grid.resolution, 64);
  const BuiltinSpec random = parse_builtin_spec("builtin:csg@random:5000");
  EXPECT_TRUE(random.random);
  EXPECT_EQ(random.count, 5000u);
  EXPECT_THROW(parse_builtin_spec("builtin:teapot@32"), Error);
  EXPECT_THROW(parse_builtin_spec("builtin:torus"), Error);
  EXPECT_THROW(parse_builtin_spec("builtin:torus@x"), Error);
  EXPECT_THROW(parse_builtin_spec("builtin:torus@1"), Error);
  EXPECT_THROW(parse_builtin_spec("builtin:torus@random:2"), Error);
  EXPECT_THROW(parse_builtin_spec("builtin:torus@random:100000000000"),
               Error);  // not "out of memory"
}

TEST(BuiltinShapes, RandomSamplesAreReproducible) {
  const auto shape = make_builtin_shape("sphere");
  const Samples a = sample_random(*shape, 100, Bounds{}, 5),
                b = sample_random(*shape, 100, Bounds{}, 5),
                c = sample_random(*shape, 100, Bounds{}, 6);
  EXPECT_EQ(a.points, b.points);
  EXPECT_NE(a.points, c.points);
  EXPECT_LE(a.points.maxCoeff(), 1.0);
  EXPECT_GE(a.points.minCoeff(), -1.0);
}
