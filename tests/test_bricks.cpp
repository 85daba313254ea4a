#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "contact_points/brick_geometry.h"
#include "contact_points/brick_shell.h"
#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

// The global computation the bricks must reproduce.
ContactPoints global_contact_points(const BandSamples& band, const ContactPointOptions& contact) {
  const Samples& s = band.samples;
  const Triangulation tri = triangulate(s.points, s.values);
  const PointMatrix g = vertex_gradients(s.points, s.values, tri, GradientOptions{});
  return gradient_contact_points(s.points, s.values, g, tri, contact, &band.core);
}

void expect_same(const ContactPoints& a, const ContactPoints& b) {
  ASSERT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.hidden, b.hidden);
  EXPECT_EQ(a.zero_gradient, b.zero_gradient);
  EXPECT_EQ(a.discarded, b.discarded);
  EXPECT_EQ(a.rescued, b.rescued);
  // Bit for bit: the same stars, summed in the same order.
  EXPECT_EQ((a.points - b.points).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((a.normals - b.normals).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace

// Bricks give exactly the global triangulation's contact points, on a grid's band and on
// scattered samples, with small bricks and a thin first halo so that retries happen.
TEST(Bricks, EqualTheGlobalTriangulation) {
  for (const auto& [name, fn] : {std::pair<std::string, bool>{"torus", false}, {"box", true}}) {
    SCOPED_TRACE(name);
    const Grid grid = sample_grid(*make_builtin_shape(name), 32, Bounds{});
    const BandSamples band = select_band(grid, BandOptions{});
    ContactPointOptions contact;
    contact.try_tet_gradients = fn;
    const ContactPoints global = global_contact_points(band, contact);
    BrickOptions o;
    o.size = 12;
    o.halo = 5;
    BrickStats stats;
    const ContactPoints bricks =
        brick_contact_points(band.samples, band.spacing, {}, contact, o, &stats, {}, &band.core);
    std::cout << name << ": " << stats.bricks << " bricks, " << stats.retries << " retries, "
              << stats.triangulated << " samples triangulated for " << band.samples.values.size()
              << "\n";
    EXPECT_GT(stats.bricks, 8);
    EXPECT_GT(stats.retries, 0);
    expect_same(bricks, global);
  }
  // Scattered samples.
  const auto shape = make_builtin_shape("csg");
  const Samples random = sample_random(*shape, 4000, Bounds{}, 5);
  const BandSamples band = select_band(random, BandOptions{});
  BrickOptions o;
  o.size = 5;
  o.halo = 3;
  BrickStats stats;
  expect_same(brick_contact_points(band.samples, band.spacing, {}, {}, o, &stats, {}, &band.core),
              global_contact_points(band, {}));
  EXPECT_GT(stats.bricks, 8);
}

// Two objects a billion spacings apart: only bricks that hold samples exist, so memory and time
// follow the samples, not the empty space between them, and both objects get their contact points.
TEST(Bricks, ObjectsFarApartCostTheirSamplesOnly) {
  const auto torus = make_builtin_shape("torus");
  const Grid grid = sample_grid(*torus, 20, Bounds{});
  const BandSamples near = select_band(grid, BandOptions{});
  const Eigen::Index n = near.samples.points.rows();
  const double shift = 1e9 * near.spacing;
  Samples both = near.samples;
  both.points.conservativeResize(2 * n, 3);
  both.values.conservativeResize(2 * n);
  both.points.bottomRows(n) = near.samples.points.rowwise() + Eigen::RowVector3d(shift, 0, 0);
  both.values.tail(n) = near.samples.values;
  std::vector<char> core = near.core;
  core.insert(core.end(), near.core.begin(), near.core.end());
  BrickOptions o;
  o.size = 8;
  o.halo = 4;
  BrickStats stats;
  const ContactPoints cp = brick_contact_points(both, near.spacing, {}, {}, o, &stats, {}, &core);
  EXPECT_LT(stats.bricks, 100);
  const ContactPoints alone =
      brick_contact_points(near.samples, near.spacing, {}, {}, o, nullptr, {}, &near.core);
  long far = 0;
  for (Eigen::Index r = 0; r < cp.points.rows(); ++r) {
    Eigen::Vector3d c = cp.points.row(r).transpose();
    if (c.x() > shift / 2) c.x() -= shift, ++far;
    EXPECT_LT(std::abs(torus->distance(c)), 0.5 * near.spacing);
  }
  EXPECT_NEAR(double(far), double(alone.size()), 0.02 * double(alone.size()));
  EXPECT_NEAR(double(cp.size() - far), double(alone.size()), 0.02 * double(alone.size()));
}

// The automatic side: the largest candidate that still gives 4 bricks per thread, and the
// automatic bricks' contact points are the global ones.
TEST(Bricks, AutomaticSizeKeepsFourBricksPerThread) {
  // A plane of points 1000 spacings wide (spacing 1): 256-spacing bricks make 4 x 4 of them.
  PointMatrix plane(200 * 200, 3);
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) plane.row(i * 200 + j) << 5.0 * i, 5.0 * j, 0.0;
  EXPECT_EQ(auto_brick_size(plane, 1.0, 1), 256);  // 16 bricks
  EXPECT_EQ(auto_brick_size(plane, 1.0, 8), 192);  // 6 x 6 = 36 >= 32
  EXPECT_EQ(auto_brick_size(plane, 1.0, 64), 64);  // no candidate makes 256 bricks
  EXPECT_THROW(auto_brick_size(plane, 0.0, 1), Error);

  const Grid grid = sample_grid(*make_builtin_shape("torus"), 32, Bounds{});
  const BandSamples band = select_band(grid, BandOptions{});
  BrickOptions o;  // size automatic
  o.halo = auto_brick_halo(band.samples.values.cwiseAbs().maxCoeff(), band.spacing);
  BrickStats stats;
  expect_same(brick_contact_points(band.samples, band.spacing, {}, {}, o, &stats, {}, &band.core),
              global_contact_points(band, {}));
  EXPECT_EQ(stats.size, 64);  // a 32^3 band is one brick of any candidate size
}

TEST(Bricks, RejectBadOptions) {
  const Grid grid = sample_grid(*make_builtin_shape("sphere"), 12, Bounds{});
  const BandSamples band = select_band(grid, BandOptions{});
  BrickOptions o;
  o.size = 0;
  EXPECT_THROW(brick_contact_points(band.samples, band.spacing, {}, {}, o), Error);
  o.size = 8;
  o.halo = 0;
  EXPECT_THROW(brick_contact_points(band.samples, band.spacing, {}, {}, o), Error);
}

// Tetrahedra of grid samples on one diagonal plane (made tetrahedra by the rounding of their
// coordinates, too flat for a floating-point orthocentre) and samples on the band's convex hull
// where a grid's side cuts it are certified in place: no brick falls back to triangulating every
// sample, and the result is still the global one.
TEST(Bricks, CertifyHullSamplesAndFlatTetrahedraInPlace) {
  // The last grid cuts the sphere at x = 0.4: its band ends on the grid's side, a flat face of
  // the hull.
  Bounds cut;
  cut.max.x() = 0.4;
  for (const auto& [n, bounds] : {std::pair{72, Bounds{}}, {96, Bounds{}}, {72, cut}}) {
    SCOPED_TRACE(n);
    const Grid grid = sample_grid(*make_builtin_shape("sphere"), n, bounds);
    BandOptions band_options;
    band_options.band = 3;
    const BandSamples band = select_band(grid, band_options);
    BrickOptions o;
    o.size = 24;
    // A halo of twice the largest |value| holds every star here, so any retry would be a hull
    // sample or a flat tet that was not certified.
    const double largest = band.samples.values.cwiseAbs().maxCoeff();
    o.halo = 2 * largest / band.spacing;
    BrickStats stats;
    const ContactPoints bricks =
        brick_contact_points(band.samples, band.spacing, {}, {}, o, &stats, {}, &band.core);
    std::cout << n << "^3: " << stats.bricks << " bricks, " << stats.retries << " retries, largest "
              << stats.largest_brick << " of " << band.samples.values.size() << " samples\n";
    EXPECT_EQ(stats.retries, 0);
    EXPECT_LT(stats.largest_brick, band.samples.values.size() / 2);
    const ContactPoints global = global_contact_points(band, {});
    expect_same(bricks, global);
    // The automatic halo is thinner: a few stars reach beyond it, and their samples are solved
    // again in small boxes, so that the halo's savings are kept.
    o.halo = auto_brick_halo(largest, band.spacing);
    BrickStats thin;
    expect_same(brick_contact_points(band.samples, band.spacing, {}, {}, o, &thin, {}, &band.core),
                global);
    std::cout << "  automatic halo " << o.halo << ": " << thin.retries << " retries, "
              << thin.triangulated << " samples triangulated, against " << stats.triangulated
              << "\n";
    EXPECT_LT(thin.triangulated, stats.triangulated);
  }
}

// The exact orthocentre of a tetrahedron one coordinate's last bit away from flat: four points
// on the plane x = z with equal power from one point of that plane (as grid samples of a distance
// field are), one moved off by an ulp. The floating-point solve divides noise by noise; the
// exact centre has equal power to all four and lies on the axis through that point.
TEST(BrickGeometry, ExactOrthocentreOfANearlyFlatTetrahedron) {
  const Eigen::Vector3d a(0.1, 0, 0.1), b(1.1, 0, 1.1), c(1.1, 1, 1.1);
  const Eigen::Vector3d d(std::nextafter(0.1, 1.0), 1, 0.1);
  const Eigen::Vector3d m(0.4, 0.6, 0.4);
  Eigen::Vector4d w;
  int i = 0;
  for (const Eigen::Vector3d& p : {a, b, c, d}) w[i++] = (p - m).squaredNorm() - 0.1;
  Eigen::Vector3d centre;
  ASSERT_TRUE(exact_orthocentre(a, b, c, d, w, centre));
  i = 0;
  for (const Eigen::Vector3d& p : {a, b, c, d})
    EXPECT_NEAR((centre - p).squaredNorm() - w[i++], (centre - a).squaredNorm() - w[0], 1e-9);
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 0, -1).normalized();
  const Eigen::Vector3d off = centre - m;
  EXPECT_NEAR((off - off.dot(axis) * axis).norm(), 0.0, 1e-9);
  EXPECT_LT(off.norm(), 100.0);  // the weights' rounding moves it along the axis, not to infinity
  // Exactly coplanar points have none.
  EXPECT_FALSE(exact_orthocentre(a, b, c, Eigen::Vector3d(0.1, 1, 0.1), w, centre));
}

// A facet of a local hull is a global one only if no point of the global hull lies beyond or
// on its plane (other than its own corners).
TEST(BrickGeometry, GlobalHullFacets) {
  // The unit cube's corners and its centre; hull vertices are the corners.
  PointMatrix points(9, 3);
  for (int i = 0; i < 8; ++i) points.row(i) << (i & 1), ((i >> 1) & 1), ((i >> 2) & 1);
  points.row(8) << 0.5, 0.5, 0.5;
  const std::vector<std::vector<int>> buckets{{0, 1, 2, 3, 8}, {4, 5, 6, 7}};
  const std::vector<Eigen::Vector3d> hull = convex_hull_vertices(points, buckets);
  EXPECT_EQ(hull.size(), 8u);
  const Eigen::Vector3d inner(0.5, 0.5, 0.5);
  // Half of the bottom face: the corner (1,1,0) lies on its plane.
  EXPECT_EQ(classify_hull_facet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, inner, hull),
            HullFacet::InGlobalFace);
  // A plane cutting a corner off: (1,1,1) lies beyond it.
  EXPECT_EQ(classify_hull_facet({1, 0, 1}, {0, 1, 1}, {1, 1, 0}, inner, hull),
            HullFacet::NotGlobal);
  // A tetrahedron's hull: each face is a global facet seen from the opposite corner.
  const std::vector<Eigen::Vector3d> tet{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_EQ(classify_hull_facet({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}, tet),
            HullFacet::Global);
  EXPECT_EQ(classify_hull_facet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, tet),
            HullFacet::Global);
  EXPECT_EQ(classify_hull_facet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}, tet),
            HullFacet::NotGlobal);
}

// The hull from the columns' ends (convex_hull_vertices keeps of each run of points with the
// same x and y only its two ends) is CGAL's hull of every point: a grid's band around a sphere,
// with scattered points among it, in buckets of any shape.
TEST(BrickGeometry, HullFromColumnEndsIsTheHullOfEveryPoint) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> rows;
  const double h = 2.0 / 23;
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 24; ++j)
      for (int k = 0; k < 24; ++k) {
        const Eigen::Vector3d p(-1 + i * h, -1 + j * h, -1 + k * h);
        if (std::abs(p.norm() - 0.7) <= 3 * h) rows.push_back(p);
      }
  for (int r = 0; r < 300; ++r) rows.emplace_back(0.8 * u(rng), 0.8 * u(rng), 0.8 * u(rng));
  PointMatrix points(Eigen::Index(rows.size()), 3);
  for (std::size_t r = 0; r < rows.size(); ++r) points.row(Eigen::Index(r)) = rows[r].transpose();
  std::vector<std::vector<int>> buckets(5);
  for (int r = 0; r < points.rows(); ++r) buckets[std::size_t(r % 5)].push_back(r);
  auto sorted = [](std::vector<std::array<double, 3>> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  std::vector<std::array<double, 3>> ours, all;
  for (const Eigen::Vector3d& p : convex_hull_vertices(points, buckets))
    ours.push_back({p.x(), p.y(), p.z()});
  std::vector<K::Point_3> every, hull;
  for (const Eigen::Vector3d& p : rows) every.emplace_back(p.x(), p.y(), p.z());
  CGAL::extreme_points_3(every, std::back_inserter(hull));
  for (const K::Point_3& p : hull) all.push_back({p.x(), p.y(), p.z()});
  EXPECT_GT(all.size(), 8u);
  EXPECT_EQ(sorted(ours), sorted(all));
}

// The shell's test against brute force: a sample q conflicts with the sphere (c, r2) when
// |c - q|^2 - w_q < r2. Random samples in a box's shell, random spheres (some imaginary); a
// conflict is never missed, and a sphere is passed whenever its nearest conflict is clearly
// apart (more than the margin's worth).
TEST(BrickGeometry, ShellFindsEveryConflictingSample) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const BrickBox box{Eigen::Vector3d::Constant(-0.5), Eigen::Vector3d::Constant(0.5)};
  const BrickBox outer{Eigen::Vector3d::Constant(-1.0), Eigen::Vector3d::Constant(1.0)};
  PointMatrix points(3000, 3);
  Eigen::VectorXd values(3000);
  std::vector<int> outside;
  for (int i = 0; i < 3000; ++i) {
    points.row(i) << u(rng), u(rng), u(rng);
    values[i] = 0.1 * u(rng);
    if (!box.contains(Eigen::Vector3d(points.row(i).transpose()))) outside.push_back(i);
  }
  const BrickShell shell(points, values, outside, outer, 0.05);
  EXPECT_FALSE(shell.empty());
  const double margin = 1e-9, max_weight = 0.01;
  int conflicts = 0, free = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Vector3d c(0.6 * u(rng), 0.6 * u(rng), 0.6 * u(rng));
    const double r2 = 0.02 * u(rng);                           // negative: an imaginary sphere
    double closest = std::numeric_limits<double>::infinity();  // min |c - q|^2 - w_q - r2
    for (int q : outside)
      closest = std::min(closest, (Eigen::Vector3d(points.row(q).transpose()) - c).squaredNorm() -
                                      values[q] * values[q] - r2);
    const double reach = std::sqrt(std::max(r2 + max_weight, 0.0)) + margin;
    const bool clear = shell.conflict_free(c, r2, reach, margin);
    if (closest < 0) {
      EXPECT_FALSE(clear) << trial;
    } else if (closest > 1e-6) {
      EXPECT_TRUE(clear) << trial;
    }
    (clear ? free : conflicts) += 1;
  }
  EXPECT_GT(conflicts, 100);
  EXPECT_GT(free, 100);
}
