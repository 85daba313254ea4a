// Contact points from a grid's lattice (lattice_contact_points.h) against the regular
// triangulation's, and the empty-sphere property that defines them.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <map>
#include <random>

#include "contact_points/lattice_gradient.h"
#include "contact_points/lattice_spheres.h"
#include "metrics/statistics.h"
#include "reconstruction/carving_internal.h"
#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/signed_distance.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/local_brick.h"
#include "test_support.h"

using namespace sdfcontour;
using Eigen::Vector3d;

namespace {

// The local reconstruction's contact-point options (local_stage.cpp), as the bricks run them
// with the triangulation's tie tolerance.
ContactPointOptions local_contact() {
  return local_brick_options(ContourOptions{}).contact;
}

// ... and as they run the lattice's points by default (kLatticeTieTolerance, fewer slides).
ContactPointOptions default_lattice_contact() {
  return local_brick_options(ContourOptions{}).lattice_contact;
}

BandSamples band_of(const Grid& g, double band = 8) {
  BandOptions o;
  o.band = band;
  o.truncation_mode = TruncationMode::None;
  return select_band(g, o);
}

// The regular triangulation's points of the band's core samples, as contour() computes them
// without bricks (the margin's weights capped).
ContactPoints regular_points(const BandSamples& band, const ContactPointOptions& contact) {
  const Samples& s = band.samples;
  const Triangulation t = triangulate(
      s.points, capped_weight_values(s.values, band.core_inside, band.core_outside), {});
  const PointMatrix g = vertex_gradients(s.points, s.values, t, {}, &band.core);
  return gradient_contact_points(s.points, s.values, g, t, contact, &band.core);
}

std::vector<double> errors(const ContactPoints& cp, const AnalyticShape& shape, double h) {
  std::vector<double> e;
  for (Eigen::Index i = 0; i < cp.points.rows(); ++i)
    e.push_back(std::abs(shape.distance(cp.points.row(i).transpose())) / h);
  return e;
}

// Brute force: the deepest that any band sample's sphere but sample s's own holds c, less the
// tie tolerance's allowance.
double deepest_hold(const BandSamples& band, long s, const Vector3d& c, double tau) {
  const Vector3d p = band.samples.points.row(s).transpose();
  double deepest = -INFINITY;
  for (Eigen::Index j = 0; j < band.samples.values.size(); ++j) {
    if (j == s) continue;
    const Vector3d q = band.samples.points.row(j).transpose();
    const double radius = std::abs(band.samples.values[j]) - tau * (q - p).norm();
    deepest = std::max(deepest, radius - (c - q).norm());
  }
  return deepest;
}

// axis_slope() at x = 0 of f sampled every h along an axis, with the samples before offset
// -cut beyond the grid's side (cut 3: none).
template <class F>
bool slope_along(const F& f, double h, int cut, double& slope) {
  detail::lattice_points::AxisStencil s;
  for (int k = -2; k <= 2; ++k) {
    s.has[std::size_t(k + 2)] = k >= -cut;
    s.v[std::size_t(k + 2)] = f(k * h);
  }
  auto far = [&](int offset, double& out) {
    if (offset < -cut) return false;
    out = f(offset * h);
    return true;
  };
  return detail::lattice_points::axis_slope(s, h, far, slope);
}

}  // namespace

TEST(LatticeContactPoints, EqualTheRegularTriangulationsOnAPlane) {
  // A tilted plane: both gradients are exact, every point lies on the plane.
  Grid g = sample_grid(*make_builtin_shape("sphere"), 24, Bounds{});
  const Vector3d n = Vector3d(0.3, -0.5, 0.8).normalized();
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 24; ++j)
      for (int k = 0; k < 24; ++k)
        g.values[Eigen::Index(g.index(i, j, k))] = n.dot(g.point(i, j, k)) - 0.1;
  const BandSamples band = band_of(g, 4);
  const ContactPoints lattice = lattice_contact_points(g, band, {});
  const ContactPoints regular = regular_points(band, {});
  const long core = std::count(band.core.begin(), band.core.end(), 1);
  EXPECT_EQ(lattice.size(), core);  // no sphere holds a point of the plane
  ASSERT_GT(regular.size(), 1000);
  int compared = 0;
  for (int a = 0, b = 0; a < regular.size(); ++a) {
    while (b < lattice.size() && lattice.samples[std::size_t(b)] < regular.samples[std::size_t(a)])
      ++b;
    ASSERT_LT(b, lattice.size());
    ASSERT_EQ(lattice.samples[std::size_t(b)], regular.samples[std::size_t(a)]);
    EXPECT_LT((lattice.points.row(b) - regular.points.row(a)).norm(), 1e-12);
    EXPECT_LT((lattice.normals.row(b) - n.transpose()).norm(), 1e-12);
    ++compared;
  }
  EXPECT_EQ(compared, regular.size());
}

TEST(LatticeContactPoints, AsCloseAsTheRegularTriangulationsOnASphereAndABox) {
  for (const std::string name : {"sphere", "box", "torus"}) {
    const auto shape = make_builtin_shape(name);
    const Grid g = sample_grid(*shape, 40, Bounds{});
    const double h = g.spacing().maxCoeff();
    const BandSamples band = band_of(g);
    const ContactPoints lattice = lattice_contact_points(g, band, local_contact());
    const ContactPoints regular = regular_points(band, local_contact());
    const std::vector<double> el = errors(lattice, *shape, h), er = errors(regular, *shape, h);
    std::cout << name << " 40^3: lattice " << lattice.size() << " points, median "
              << quantile(el, 0.5) << " h, p95 " << quantile(el, 0.95) << " h; regular "
              << regular.size() << ", " << quantile(er, 0.5) << " h, " << quantile(er, 0.95)
              << " h\n";
    EXPECT_LE(quantile(el, 0.5), quantile(er, 0.5) * 1.01 + 1e-9) << name;
    EXPECT_LE(quantile(el, 0.95), quantile(er, 0.95) * 1.01 + 1e-9) << name;
    EXPECT_GE(lattice.size(), 0.95 * regular.size()) << name;
    // The default's looser tie keeps more points; those it keeps are held by at most a
    // thousandth of a spacing or so, so the tail stays and the median moves by about that.
    const ContactPoints loose = lattice_contact_points(g, band, default_lattice_contact());
    const std::vector<double> eo = errors(loose, *shape, h);
    std::cout << name << " 40^3, tie " << default_lattice_contact().tie_tolerance << ": "
              << loose.size() << " points, median " << quantile(eo, 0.5) << " h, p95 "
              << quantile(eo, 0.95) << " h\n";
    EXPECT_GE(loose.size(), lattice.size()) << name;
    EXPECT_LE(quantile(eo, 0.95), quantile(er, 0.95) * 1.01 + 1e-9) << name;
    EXPECT_LE(quantile(eo, 0.5), quantile(er, 0.5) + 2e-3) << name;
  }
}

TEST(LatticeContactPoints, NoKeptPointLiesInAnotherSamplesSphere) {
  // Random grids: smooth fields, random signs, noise and clamps; with the paper's options and the
  // local reconstruction's (slides and near misses allowed their stated depth).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 6 + trial % 5;
    Grid g = sample_grid(*make_builtin_shape(trial % 2 ? "csg" : "torus"), n, Bounds{});
    for (Eigen::Index i = 0; i < g.values.size(); ++i) {
      if (trial % 3 == 1) g.values[i] += 0.3 * u(rng);
      if (trial % 3 == 2) g.values[i] = u(rng);
    }
    const BandSamples band = band_of(g, trial % 4 + 1);
    for (const int options : {0, 1, 2}) {
      const bool local = options > 0;
      const ContactPointOptions o = options == 0   ? ContactPointOptions{}
                                    : options == 1 ? local_contact()
                                                   : default_lattice_contact();
      const ContactPoints cp = lattice_contact_points(g, band, o);
      for (int a = 0; a < cp.size(); ++a) {
        const long s = cp.samples[std::size_t(a)];
        // (A slid point or a power vertex may lie in spheres that nearly meet there: its power
        // within the tolerance of value^2, a depth of about half that fraction of |value|; a
        // power vertex is that close to its own sphere too.)
        const double allowed =
            local ? o.power_vertex_tolerance / 2 * std::abs(band.samples.values[s]) : 0.0;
        EXPECT_LE(deepest_hold(band, s, cp.points.row(a).transpose(), o.tie_tolerance), allowed)
            << "trial " << trial << " sample " << s;
        EXPECT_NEAR((cp.points.row(a) - band.samples.points.row(s)).norm(),
                    std::abs(band.samples.values[s]), 1e-9 + allowed);
      }
    }
  }
}

TEST(LatticeContactPoints, RescuesStopAtTheirReach) {
  // Each sample's point depends on the lattice alone, not on the other samples' outcomes: beyond
  // the reach the slide and the power vertex go, and nothing else changes.
  const Grid g = sample_grid(*make_builtin_shape("csg"), 40, Bounds{});
  const BandSamples band = band_of(g, 8);
  const double h = g.spacing().maxCoeff(), reach = 3;
  ContactPointOptions o = default_lattice_contact();
  o.rescue_reach = 0;
  const ContactPoints all = lattice_contact_points(g, band, o);
  o.rescue_reach = reach;
  const ContactPoints near = lattice_contact_points(g, band, o);
  std::map<long, int> row_of;
  for (int a = 0; a < all.size(); ++a) row_of[all.samples[std::size_t(a)]] = a;
  for (int a = 0; a < near.size(); ++a) {
    const auto it = row_of.find(near.samples[std::size_t(a)]);
    ASSERT_NE(it, row_of.end()) << near.samples[std::size_t(a)];
    EXPECT_EQ(near.points.row(a), all.points.row(it->second));
    EXPECT_EQ(near.normals.row(a), all.normals.row(it->second));
    row_of.erase(it);
  }
  // What is left: the rescues of samples beyond the reach.
  ASSERT_GT(row_of.size(), 20u);
  EXPECT_EQ(long(row_of.size()), long(all.rescued) - near.rescued);
  for (const auto& [sample, row] : row_of)
    EXPECT_GT(std::abs(band.samples.values[sample]), reach * h) << sample;
  o.rescue_reach = -1;
  EXPECT_THROW(lattice_contact_points(g, band, o), Error);
}

TEST(LatticeContactPoints, LocalBricksEqualOneBrick) {
  // A CSG shape (edges, corners, a hole) at 40^3: bricks of 13 and 20 samples cut through its
  // features and corners. (Each brick reads its block with the repair stages' halo, ~60 samples:
  // at 40^3 bricks of 8 cost 125 times the whole grid's work.)
  const Grid g = sample_grid(*make_builtin_shape("csg"), 40, Bounds{});
  LocalBrickOptions o = local_brick_options(ContourOptions{});
  o.band.truncation_mode = TruncationMode::None;
  o.lattice_points = true;
  o.subdivisions = 1;
  o.thin_parts = 0;
  const Mesh whole = local_mesh_in_bricks(view_of(g), o, 0);
  ASSERT_GT(whole.triangles.rows(), 1000);
  test::expect_closed_and_outward(whole);
  for (const auto& [brick, threads] : {std::pair{13, 1}, std::pair{20, 2}}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const Mesh m = local_mesh_in_bricks(view_of(g), o, brick);
    EXPECT_EQ(m.vertices, whole.vertices) << brick;
    EXPECT_EQ(m.triangles, whole.triangles) << brick;
  }
}

TEST(LatticeContactPoints, EdgeFannedBricksReadTheirBlocksOnce) {
  // With the edge fans (no repair ring) the halo is the lattice's reach: each brick's block holds
  // what its points read, the first time (a halo one sample short made 7 of bunny 512^3's 8
  // bricks read theirs again), and the bricks give the whole grid's mesh.
  const Grid g = sample_grid(*make_builtin_shape("torus"), 64, Bounds{});
  ContourOptions c;
  c.local.edge_fans = true;
  LocalBrickOptions o = local_brick_options(c);
  o.lattice_points = true;
  o.subdivisions = 0;
  o.thin_parts = 0;
  o.band.band = 2;  // (a whole number of spacings with the margin: the halo is the lattice's)
  const Mesh whole = local_mesh_in_bricks(view_of(g), o, 0);
  LocalBricksStats stats;
  const Mesh m = local_mesh_in_bricks(view_of(g), o, 24, &stats);
  EXPECT_GT(stats.bricks, 8);
  EXPECT_EQ(stats.wider_halos, 0);
  EXPECT_EQ(m.vertices, whole.vertices);
  EXPECT_EQ(m.triangles, whole.triangles);
}

TEST(LatticeContactPoints, TheDefaultTakesTheLatticeFrom64SamplesPerAxis) {
  // --gradient auto: the lattice's points with their tie tolerance from 64 samples per axis (the
  // whole grid's longest), the triangulation's below; each is the explicit choice bit for bit.
  const auto torus = make_builtin_shape("torus");
  for (const int n : {48, 64}) {
    const Grid g = sample_grid(*torus, n, Bounds{});
    const ContourResult automatic = contour(grid_input(g), ContourOptions{});
    ContourOptions regular, lattice;
    regular.gradient_source = GradientSource::Regular;
    lattice.gradient_source = GradientSource::Lattice;
    const ContourResult chosen = contour(grid_input(g), n >= 64 ? lattice : regular);
    const ContourResult other = contour(grid_input(g), n >= 64 ? regular : lattice);
    ASSERT_TRUE(automatic.local_bricks && chosen.mesh && other.mesh);
    EXPECT_EQ(automatic.local_bricks->lattice_points, n >= 64) << n;
    EXPECT_EQ(automatic.mesh->vertices, chosen.mesh->vertices) << n;
    EXPECT_EQ(automatic.mesh->triangles, chosen.mesh->triangles) << n;
    EXPECT_NE(automatic.mesh->vertices, other.mesh->vertices) << n;
  }
  // A grid of 64 along one axis alone counts by that axis; values that are no distances (the
  // zero set refined) keep the triangulation.
  LocalBrickOptions o;
  EXPECT_TRUE(local_lattice_points(o, {64, 8, 8}));
  EXPECT_FALSE(local_lattice_points(o, {63, 63, 63}));
  o.refine_zero_set = true;
  EXPECT_FALSE(local_lattice_points(o, {128, 128, 128}));
  o.lattice_points = 1;
  EXPECT_TRUE(local_lattice_points(o, {32, 32, 32}));
}

TEST(LatticeContactPoints, TheSphereSearchFindsWhatBruteForceFinds) {
  // Random values keep random samples in the band: columns with several runs and gaps, and
  // empty ones. Every sphere that comes within `extra` of a query point, in the band's order.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 6; ++trial) {
    const int n = 7 + trial;
    Grid g = sample_grid(*make_builtin_shape("torus"), n, Bounds{});
    for (Eigen::Index i = 0; i < g.values.size(); ++i)
      if (trial % 2 || u(rng) > 0.5) g.values[i] = 0.5 * u(rng);
    const BandSamples band = band_of(g, 1 + trial % 3);
    const detail::Lattice lattice(g, band);
    const double h = g.spacing().maxCoeff();
    const Eigen::Index m = band.samples.values.size();
    for (int query = 0; query < 200; ++query) {
      const Vector3d c(1.1 * u(rng), 1.1 * u(rng), 1.1 * u(rng));
      const double extra = query % 2 ? 0.3 * h : 0.0;
      const long self = query % 3 == 0 && m > 0 ? long(rng() % std::uint32_t(m)) : -1;
      std::vector<long> found;
      lattice.any_sphere_near(c, extra, self, [&](long t, double d2) {
        EXPECT_NEAR(d2, (c - band.samples.points.row(t).transpose()).squaredNorm(), 1e-12);
        found.push_back(t);
        return false;
      });
      std::vector<long> expected;
      for (Eigen::Index t = 0; t < m; ++t) {
        const double d = (c - band.samples.points.row(t).transpose()).norm();
        const double r = std::abs(band.samples.values[t]) + extra;
        if (t != self && d < r) expected.push_back(long(t));
      }
      EXPECT_EQ(found, expected) << "trial " << trial << " query " << query;
      // The list gathered for a box around c gives the same spheres in the same order, with the
      // same squared distances, wherever it covers c.
      detail::SphereList list;
      const Vector3d below(u(rng) + 1, u(rng) + 1, u(rng) + 1), above(u(rng) + 1, u(rng) + 1, 0);
      lattice.gather(c - 0.7 * h * below, c + 0.7 * h * above, 0.3 * h, list);
      ASSERT_TRUE(list.covers(c, extra));
      EXPECT_FALSE(list.covers(c, 0.31 * h));
      EXPECT_FALSE(list.covers(c + Vector3d(0, 0, 0.7 * h * above[2] + 0.31 * h), 0.0));
      std::vector<std::pair<long, double>> from_list, from_lattice;
      list.any_sphere_near(c, extra, self, [&](long t, double d2) {
        from_list.emplace_back(t, d2);
        return false;
      });
      lattice.any_sphere_near(c, extra, self, [&](long t, double d2) {
        from_lattice.emplace_back(t, d2);
        return false;
      });
      EXPECT_EQ(from_list, from_lattice) << "trial " << trial << " query " << query;
    }
    // The samples along each column, against the band's own indices.
    std::vector<long> at(std::size_t(g.values.size()), -1);
    for (Eigen::Index t = 0; t < m; ++t) at[std::size_t(band.source[std::size_t(t)])] = long(t);
    std::vector<long> column(std::size_t(n) + 4);
    for (int i = -1; i <= n; ++i)
      for (int j = -1; j <= n; ++j) {
        lattice.along(i, j, -2, n + 1, column.data());
        for (int k = -2; k <= n + 1; ++k) {
          const bool inside = i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n;
          const long want = inside ? at[std::size_t((i * n + j) * n + k)] : -1;
          ASSERT_EQ(column[std::size_t(k + 2)], want) << i << " " << j << " " << k;
        }
      }
  }
}

TEST(LatticeContactPoints, TheLatticesBallsPushAsTheBallsAlone) {
  // Carving's deepest pushes read box by box from the lattice against the ball-driven search:
  // the same moves, bit for bit, on exact and on perturbed values, for all vertices or a few.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 4; ++trial) {
    const int n = 12 + 5 * trial;
    Grid g = sample_grid(*make_builtin_shape(trial % 2 ? "torus" : "sphere"), n, Bounds{});
    const double h = g.spacing().maxCoeff();
    if (trial >= 2)
      for (Eigen::Index i = 0; i < g.values.size(); ++i) g.values[i] += 0.3 * h * u(rng);
    const BandSamples band = band_of(g, 2 + trial);
    const detail::Lattice lattice(g, band);
    // Vertices near the surface (the balls' samples moved by up to their values and more).
    PointMatrix V(1500, 3);
    for (Eigen::Index v = 0; v < V.rows(); ++v) {
      const Eigen::Index s = Eigen::Index(rng() % std::uint32_t(band.samples.values.size()));
      const Vector3d dir = Vector3d(u(rng), u(rng), u(rng)).normalized();
      V.row(v) = band.samples.points.row(s) +
                 (std::abs(band.samples.values[s]) * (1 + 0.2 * u(rng))) * dir.transpose();
    }
    std::vector<int> all(std::size_t(V.rows())), some;
    for (int v = 0; v < int(V.rows()); ++v) {
      all[std::size_t(v)] = v;
      if (v % 7 == 0) some.push_back(v);
    }
    for (const auto* which : {&all, &some}) {
      const PointMatrix by_balls =
          detail::deepest_pushes(V, *which, band.samples.points, band.samples.values, h);
      const PointMatrix by_boxes = detail::deepest_pushes(V, *which, lattice, nullptr, h);
      long pushed = 0;
      for (Eigen::Index v = 0; v < V.rows(); ++v) pushed += by_balls.row(v).squaredNorm() > 0;
      EXPECT_GT(pushed, long(which->size()) / 10) << "trial " << trial;
      EXPECT_TRUE(by_boxes == by_balls) << "trial " << trial;
      // The band's core alone, as a brick carves: against the core's own samples.
      const Samples core = core_samples(band);
      EXPECT_LT(core.values.size(), band.samples.values.size());
      const PointMatrix by_core = detail::deepest_pushes(V, *which, core.points, core.values, h);
      EXPECT_TRUE(detail::deepest_pushes(V, *which, lattice, &band.core, h) == by_core)
          << "trial " << trial;
    }
  }
}

// A box's face samples next to its edges: their central stencils reach across the face's region
// into the edge's, where the distance curves, but one side of each stencil is exactly linear and
// gives the face's exact slope, so their points lie on the faces to rounding (the central
// stencils put them 1e-4-4e-3 h off). Samples whose nearest feature is an edge or a corner keep
// points near their feature.
TEST(LatticeContactPoints, FaceSamplesNextToAnEdgeTakeTheExactlyLinearSide) {
  const Vector3d half(0.6, 0.45, 0.35);
  const auto shape = make_builtin_shape("box");
  const Grid g = sample_grid(*shape, 48, Bounds{});
  const double h = g.spacing().maxCoeff();
  const BandSamples band = band_of(g, 4);
  const ContactPoints cp = lattice_contact_points(g, band, default_lattice_contact());
  int face_samples = 0, next_to_an_edge = 0;
  for (Eigen::Index r = 0; r < cp.points.rows(); ++r) {
    const Vector3d p = band.samples.points.row(cp.samples[std::size_t(r)]).transpose();
    const Vector3d q = p.cwiseAbs() - half;
    // Outside, beyond exactly one face's plane: the face is its nearest feature.
    if ((q.array() > 0).count() != 1) continue;
    ++face_samples;
    // Within two spacings of another face's plane: its stencil along that axis meets the edge's
    // region.
    next_to_an_edge += ((q.array() > -2.01 * h) && (q.array() <= 0)).any();
    EXPECT_LT(std::abs(shape->distance(cp.points.row(r).transpose())), 1e-12 * h)
        << "sample at " << p.transpose();
  }
  EXPECT_GT(face_samples, 2000);
  EXPECT_GT(next_to_an_edge, 200);
}

// Along an axis through a box's edge wedge and the face region beside it the distance is
// sqrt(max(x - x0, 0)^2 + c^2): flat, then curved. Every sample off the kink has the exact slope,
// from the flat side's linear values or the curved side's quadratic squares, central or one-sided,
// also where the grid's side cuts the stencil (a curved sample's forward window).
TEST(LatticeContactPoints, AxisSlopeIsExactOnALinesDistanceBesideAPlanes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double h = 0.01;
  int curved = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const double x0 = (unit(rng) - 0.5) * 8 * h, c = (0.05 + 3 * unit(rng)) * h;
    auto f = [&](double x) { return std::hypot(std::max(x - x0, 0.0), c); };
    const int cut = trial % 3 == 0 ? int(unit(rng) * 3) : 3;  // samples before the grid's side
    // (Cut within a spacing, a flat sample whose only side reaches the kink has no exact window.)
    if (cut < 2 && x0 > 0 && x0 < 3 * h) continue;
    double slope = NAN;
    ASSERT_TRUE(slope_along(f, h, cut, slope));
    const double exact = std::max(-x0, 0.0) / f(0);
    curved += x0 < 0;
    EXPECT_NEAR(slope, exact, 1e-11) << "x0 " << x0 / h << " h, c " << c / h << " h, cut " << cut;
  }
  EXPECT_GT(curved, 500);
}

// Four values that mirror each other about their middle lie on a parabola whatever the field:
// they give no exact slope. A smooth field symmetric about the point between two samples (a
// torus's mirror plane on an even grid) keeps the fourth-order slope, exact on a parabola (the
// squares' rule gave -0.140 for -0.125 here).
TEST(LatticeContactPoints, AxisSlopeIgnoresMirroredSquares) {
  const double h = 0.01, m = 0.5 * h;
  auto f = [&](double x) { return h + (x - m) * (x - m) / (8 * h); };
  double slope = NAN;
  ASSERT_TRUE(slope_along(f, h, 3, slope));
  EXPECT_NEAR(slope, -m / (4 * h), 1e-12);
}

// A box's samples whose nearest feature is an edge or a corner: their distances are a line's or a
// point's, whose squares are exactly quadratic along each axis, so their points lie on the box to
// rounding (with the fourth-order stencils 7% of them were 1e-4-2e-3 h off, the cube at 256^3).
// Within half the band: farther, the band may cut a wedge's first column off its stencils.
TEST(LatticeContactPoints, EdgeAndCornerSamplesTakeTheSquaresExactSlope) {
  const auto shape = make_builtin_shape("box");
  const Vector3d half(0.6, 0.45, 0.35);
  const Grid g = sample_grid(*shape, 48, Bounds{});
  const double h = g.spacing().maxCoeff();
  const BandSamples band = band_of(g, 8);
  const ContactPoints cp = lattice_contact_points(g, band, default_lattice_contact());
  int edges = 0, corners = 0;
  for (Eigen::Index r = 0; r < cp.points.rows(); ++r) {
    const Eigen::Index s = cp.samples[std::size_t(r)];
    const Vector3d p = band.samples.points.row(s).transpose();
    const auto beyond = ((p.cwiseAbs() - half).array() > 0).count();
    if (beyond < 2 || std::abs(band.samples.values[s]) > 4 * h) continue;
    (beyond == 2 ? edges : corners) += 1;
    EXPECT_LT(std::abs(shape->distance(cp.points.row(r).transpose())), 1e-11 * h)
        << "sample at " << p.transpose();
  }
  EXPECT_GT(edges, 500);
  EXPECT_GT(corners, 50);
}
