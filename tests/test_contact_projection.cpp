// Projection onto the contact points (contact_projection.h): vertices moved along their normals
// onto a quadric fitted to the points near them.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <random>

#include "reconstruction/carving_internal.h"
#include "reconstruction/mesh_geometry.h"
#include "sdfcontour/extraction/marching.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/metrics/metrics.h"
#include "sdfcontour/reconstruction/contact_projection.h"
#include "test_patches.h"

using namespace sdfcontour;

namespace {

constexpr double kSpacing = 0.05;

using test::flat_patch;

// `count` random points on the plane z = height over [-extent, extent]^2 with normal (0, 0, nz).
void add_plane_points(PointMatrix& P, PointMatrix& N, int count, double extent, double height,
                      double nz, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-extent, extent);
  const Eigen::Index first = P.rows();
  P.conservativeResize(first + count, 3);
  N.conservativeResize(first + count, 3);
  for (int q = 0; q < count; ++q) {
    P.row(first + q) << u(rng), u(rng), height;
    N.row(first + q) << 0, 0, nz;
  }
}

// Exact contact points of the builtin sphere (radius 0.6): `count` random directions.
void sphere_points(PointMatrix& P, PointMatrix& N, int count) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  P.resize(count, 3);
  N.resize(count, 3);
  for (int q = 0; q < count; ++q) {
    const Eigen::RowVector3d d = Eigen::RowVector3d(g(rng), g(rng), g(rng)).normalized();
    N.row(q) = d;
    P.row(q) = 0.6 * d;
  }
}

double largest_radius_error(const Mesh& m) {
  return (m.vertices.rowwise().norm().array() - 0.6).abs().maxCoeff();
}

}  // namespace

TEST(ContactProjection, PutsVerticesExactlyOnAPlane) {
  Mesh m = flat_patch(21, kSpacing / 2, 0.1 * kSpacing);
  PointMatrix P, N;
  add_plane_points(P, N, 4000, 8 * kSpacing, 0.0, 1.0, 1);
  const ContactProjectionStats st = project_to_contact_points(m, P, N, {}, kSpacing);
  EXPECT_EQ(st.vertices_moved, m.vertices.rows());
  EXPECT_NEAR(st.largest_move, 0.1 * kSpacing, 1e-12);
  EXPECT_LT(m.vertices.col(2).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ContactProjection, BringsASphereMuchCloserThanMarchingCubes) {
  // Marching cubes' sphere at 32^3 is ~1e-2 spacings off; exact contact points at ~40 per
  // square spacing bring every vertex within 1e-3 spacings (the quadric's own error is ~1e-5).
  const double h = 2.0 / 31;
  Mesh m = marching_cubes(sample_grid(*make_builtin_shape("sphere"), 32, Bounds{}));
  const double before = largest_radius_error(m);
  PointMatrix P, N;
  sphere_points(P, N, int(40 * 4 * M_PI * 0.36 / (h * h)));
  project_to_contact_points(m, P, N, {}, h);
  EXPECT_GT(before, 5e-3 * h);
  EXPECT_LT(largest_radius_error(m), 1e-3 * h);
}

TEST(ContactProjection, LeavesFarFitsAndFewPointsAlone) {
  PointMatrix P, N;
  add_plane_points(P, N, 4000, 8 * kSpacing, 0.0, 1.0, 2);
  // Half a spacing above the points: beyond max_move (0.25).
  Mesh far = flat_patch(5, kSpacing / 2, 0.5 * kSpacing);
  const Mesh far_before = far;
  EXPECT_EQ(project_to_contact_points(far, P, N, {}, kSpacing).vertices_moved, 0);
  EXPECT_EQ(far.vertices, far_before.vertices);
  // Points only on one side of the vertices (x > 2 spacings): the fit would extrapolate.
  PointMatrix side(0, 3), side_normals(0, 3);
  for (Eigen::Index q = 0; q < P.rows(); ++q)
    if (P(q, 0) > 0.5 * kSpacing) {
      side.conservativeResize(side.rows() + 1, 3);
      side_normals.conservativeResize(side.rows(), 3);
      side.row(side.rows() - 1) = P.row(q);
      side_normals.row(side.rows() - 1) = N.row(q);
    }
  Mesh one_sided = flat_patch(1, kSpacing, 0.1 * kSpacing);
  one_sided.vertices.row(0) << -0.5 * kSpacing, 0, 0.1 * kSpacing;
  one_sided.triangles.resize(0, 3);
  EXPECT_EQ(project_to_contact_points(one_sided, side, side_normals, {}, kSpacing).vertices_moved,
            0);
}

TEST(ContactProjection, IgnoresPointsFacingTheOtherWay) {
  // A thin part: the other side's points, 0.3 spacings above and facing down, must not pull.
  PointMatrix P, N;
  add_plane_points(P, N, 4000, 8 * kSpacing, 0.0, 1.0, 3);
  add_plane_points(P, N, 4000, 8 * kSpacing, 0.3 * kSpacing, -1.0, 4);
  Mesh m = flat_patch(11, kSpacing / 2, 0.05 * kSpacing);
  project_to_contact_points(m, P, N, {}, kSpacing);
  EXPECT_LT(m.vertices.col(2).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ContactProjection, DepthWeightsFavourNearSamples) {
  // Points of far samples (depth 6 spacings) off by 0.1 spacings, of near ones exact: with depth
  // weights the fit lands much nearer the exact plane than their plain mean (0.05).
  PointMatrix P, N;
  add_plane_points(P, N, 3000, 8 * kSpacing, 0.0, 1.0, 5);
  add_plane_points(P, N, 3000, 8 * kSpacing, 0.1 * kSpacing, 1.0, 6);
  Eigen::VectorXd depth(P.rows());
  depth.head(3000).setConstant(0.5 * kSpacing);
  depth.tail(3000).setConstant(6 * kSpacing);
  // With the default residual limit the two layers (0.05 spacings RMS from any quadric) are no
  // smooth surface: nothing moves.
  Mesh guarded = flat_patch(5, kSpacing / 2, 0.02 * kSpacing);
  EXPECT_EQ(project_to_contact_points(guarded, P, N, depth, kSpacing).vertices_moved, 0);
  ContactProjectionOptions o;
  o.max_residual = 0;
  Mesh plain = flat_patch(5, kSpacing / 2, 0.0), weighted = plain;
  project_to_contact_points(plain, P, N, depth, kSpacing, o);
  o.depth_scale = 1;
  project_to_contact_points(weighted, P, N, depth, kSpacing, o);
  EXPECT_NEAR(plain.vertices.col(2).mean(), 0.05 * kSpacing, 0.01 * kSpacing);
  EXPECT_LT(weighted.vertices.col(2).cwiseAbs().maxCoeff(), 0.01 * kSpacing);
}

TEST(ContactProjection, RobustRoundsDiscountAFewPointsOffTheSurface) {
  // Exact points on z = 0 and, as where mirror-symmetric spheres meet in a gap short of a saddle
  // (the torus's inner equator at 64^3: eight coincident points 0.07 spacings off), eight
  // coincident points 0.07 spacings above the middle: one fit lifts the middle vertices 0.023
  // spacings toward them, two robust rounds at 0.03 spacings 0.007 (measured).
  PointMatrix P, N;
  add_plane_points(P, N, 300, 1.5 * kSpacing, 0.0, 1.0, 8);
  const Eigen::Index first = P.rows();
  P.conservativeResize(first + 8, 3);
  N.conservativeResize(first + 8, 3);
  for (int q = 0; q < 8; ++q) {
    P.row(first + q) << 0, 0, 0.07 * kSpacing;
    N.row(first + q) << 0, 0, 1;
  }
  ContactProjectionOptions o = local_projection_options();
  o.robust_rounds = 0;
  Mesh plain = flat_patch(5, kSpacing / 4, 0.01 * kSpacing), robust = plain;
  project_to_contact_points(plain, P, N, {}, kSpacing, o);
  project_to_contact_points(robust, P, N, {}, kSpacing, local_projection_options());
  const double lifted = plain.vertices.col(2).cwiseAbs().maxCoeff();
  EXPECT_GT(lifted, 0.015 * kSpacing);
  EXPECT_LT(robust.vertices.col(2).cwiseAbs().maxCoeff(), std::min(0.4 * lifted, 0.01 * kSpacing));
}

namespace {

// The mean and mean absolute signed distance |x| - 0.6 from mesh `m` to the builtin sphere, over
// its area (100,000 points spread by area, one seed).
std::pair<double, double> sphere_area_distances(const Mesh& m) {
  const Eigen::VectorXd d = sample_surface(m, 100000, 1).rowwise().norm().array() - 0.6;
  return {d.mean(), d.cwiseAbs().mean()};
}

}  // namespace

TEST(ContactProjection, ChordOffsetsCentreTheMeshOnACurvedSurface) {
  // Vertices on the sphere leave its flat triangles inside it by their chords' sagitta (the
  // mean signed distance is negative); each vertex raised by its triangles' mean chord offset
  // from the fitted quadric puts the triangles across the surface.
  const double h = 2.0 / 31;
  const Mesh mc = marching_cubes(sample_grid(*make_builtin_shape("sphere"), 32, Bounds{}));
  PointMatrix P, N;
  sphere_points(P, N, int(40 * 4 * M_PI * 0.36 / (h * h)));
  ContactProjectionOptions o;
  Mesh plain = mc, chords = mc;
  project_to_contact_points(plain, P, N, {}, h, o);
  o.chord_offset = true;
  project_to_contact_points(chords, P, N, {}, h, o);
  const auto [plain_mean, plain_abs] = sphere_area_distances(plain);
  const auto [chord_mean, chord_abs] = sphere_area_distances(chords);
  std::cout << "sphere 32^3, mean signed / absolute distance: on the sphere " << plain_mean / h
            << " / " << plain_abs / h << " h, with chord offsets " << chord_mean / h << " / "
            << chord_abs / h << " h\n";
  EXPECT_LT(plain_mean, -0.9 * plain_abs);  // inside nearly everywhere
  // Measured: -0.0175 / 0.0175 h on the sphere, -0.0024 / 0.0058 h with the offsets (marching
  // cubes' uneven triangles: a vertex's offset is its triangles' mean).
  EXPECT_LT(std::abs(chord_mean), 0.25 * plain_abs);
  EXPECT_LT(chord_abs, 0.5 * plain_abs);
}

// Points on the lines y = k gap (|k| <= lines), x along them every tenth of a spacing from -4 to
// 4 spacings, at height z(y) with normal n(y): the contact points of a surface aligned with the
// grid along x.
template <class Height, class Normal>
void add_lines(PointMatrix& P, PointMatrix& N, int lines, double gap, Height z, Normal n) {
  const int per_line = 81, count = (2 * lines + 1) * per_line;
  P.resize(count, 3);
  N.resize(count, 3);
  int row = 0;
  for (int k = -lines; k <= lines; ++k)
    for (int i = -40; i <= 40; ++i, ++row) {
      const double y = k * gap;
      P.row(row) << 0.1 * i * kSpacing, y, z(y);
      N.row(row) = n(y);
    }
}

TEST(ContactProjection, AWiderFitReachesBetweenLinesOfPoints) {
  // Grid-aligned flats give contact points on lines further apart than the radius: two lines
  // leave a quadric undetermined (the vertex stays); the wider radius holds a third line and the
  // vertex lands on the cylinder z = y^2 / (2 R) the lines lie on.
  const double h = kSpacing, R = 4 * h;
  PointMatrix P, N;
  add_lines(
      P, N, 3, 1.4 * h, [&](double y) { return y * y / (2 * R); },
      [&](double y) { return Eigen::RowVector3d(0, -y / R, 1).normalized(); });
  Mesh patch = flat_patch(3, h / 20, 0);
  patch.vertices.col(1).array() += 0.5 * h;
  patch.vertices.col(2).array() += 0.5 * h * 0.5 * h / (2 * R) + 0.05 * h;
  ContactProjectionOptions o = local_projection_options();
  o.chord_offset = false;
  o.wide_radius = 0;
  Mesh narrow = patch, wide = patch;
  EXPECT_EQ(project_to_contact_points(narrow, P, N, {}, h, o).vertices_moved, 0);
  o.wide_radius = 2;
  EXPECT_EQ(project_to_contact_points(wide, P, N, {}, h, o).vertices_moved, patch.vertices.rows());
  for (Eigen::Index v = 0; v < wide.vertices.rows(); ++v) {
    const double y = wide.vertices(v, 1);
    EXPECT_LT(std::abs(wide.vertices(v, 2) - y * y / (2 * R)), 1e-3 * h) << "vertex " << v;
  }
}

TEST(ContactProjection, AnExactGridAlignedFlatNeedsNoWiderFit) {
  // A flat face aligned with the grid gives points on lines 1.1 h apart (z = 0, normals up) and,
  // 2 h away, a step up of 0.3 h (an edge of the part). The lines leave the quadric undetermined;
  // the wider fit would reach the step. The points within the radius lie on their plane with its
  // normal, so each vertex lands on z = 0, exactly.
  const double h = kSpacing;
  PointMatrix P, N;
  add_lines(
      P, N, 4, 1.1 * h, [&](double y) { return y > 1.5 * h ? 0.3 * h : 0.0; },
      [](double) { return Eigen::RowVector3d(0, 0, 1); });
  Mesh patch = flat_patch(3, h / 20, 0);
  patch.vertices.col(1).array() += 0.5 * h;
  patch.vertices.col(2).array() += 0.05 * h;
  Mesh local = patch;
  EXPECT_EQ(
      project_to_contact_points(local, P, N, {}, h, local_projection_options()).vertices_moved,
      patch.vertices.rows());
  for (Eigen::Index v = 0; v < local.vertices.rows(); ++v)
    EXPECT_LT(std::abs(local.vertices(v, 2)), 1e-12 * h) << "vertex " << v;
  // Two lines of a curved surface lie on a plane too, but their normals differ from it: those
  // still take the wider fit (AWiderFitReachesBetweenLinesOfPoints).
}

TEST(ContactProjection, SameResultWhateverTheThreadCount) {
  const double h = 2.0 / 31;
  const Mesh mc = marching_cubes(sample_grid(*make_builtin_shape("sphere"), 32, Bounds{}));
  PointMatrix P, N;
  sphere_points(P, N, 20000);
  Mesh one = mc, two = mc;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    project_to_contact_points(one, P, N, {}, h);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    project_to_contact_points(two, P, N, {}, h);
  }
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_NE(one.vertices, mc.vertices);
}

namespace {

// The sphere's exact contact points, the local reconstruction's options and marching cubes' mesh
// at 20^3, for the projector's own tests.
struct SphereFit {
  double h = 2.0 / 31;
  PointMatrix P, N;
  ContactProjectionOptions o = local_projection_options();
  Mesh coarse = marching_cubes(sample_grid(*make_builtin_shape("sphere"), 20, Bounds{}));
  SphereFit() { sphere_points(P, N, 20000); }
};

}  // namespace

TEST(ContactProjection, AProjectorMadeOnceProjectsAsTheCallEachTime) {
  // The points indexed once, then two meshes (the second with fixed vertices) and the first
  // again: each the same bits as its own call, with the local reconstruction's options.
  const SphereFit fit;
  const auto& [h, P, N, o, coarse] = fit;
  const Mesh mc = marching_cubes(sample_grid(*make_builtin_shape("sphere"), 32, Bounds{}));
  std::vector<char> fixed(std::size_t(coarse.vertices.rows()), 0);
  for (std::size_t v = 0; v < fixed.size(); v += 3) fixed[v] = 1;
  const ContactProjector projector(P, N, {}, h, o);
  Mesh a = mc, b = coarse, again = mc;
  projector.project(a);
  projector.project(b, &fixed);
  projector.project(again);
  Mesh a_call = mc, b_call = coarse;
  project_to_contact_points(a_call, P, N, {}, h, o);
  project_to_contact_points(b_call, P, N, {}, h, o, &fixed);
  EXPECT_EQ(a.vertices, a_call.vertices);
  EXPECT_EQ(b.vertices, b_call.vertices);
  EXPECT_EQ(again.vertices, a_call.vertices);
  EXPECT_NE(a.vertices, mc.vertices);
  for (std::size_t v = 0; v < fixed.size(); ++v) {
    if (fixed[v]) {
      EXPECT_EQ(b.vertices.row(Eigen::Index(v)), coarse.vertices.row(Eigen::Index(v)));
    }
  }
  const PointMatrix fewer = N.topRows(5);
  EXPECT_THROW(ContactProjector(P, fewer, {}, h, o), Error);
  const std::vector<char> short_flags(3, 0);
  EXPECT_THROW(projector.project(a, &short_flags), Error);
}

TEST(ContactProjection, TrianglesOfTheFittedVerticesAloneGiveTheSameBits) {
  // project(mesh, fixed) reads only the unfixed vertices' triangles; the caller's full lists
  // (as the split hands on) give the same bits, and a skipped vertex has none of its own.
  const SphereFit fit;
  const auto& [h, P, N, o, coarse] = fit;
  std::vector<char> fixed(std::size_t(coarse.vertices.rows()), 1);
  for (std::size_t v = 0; v < fixed.size(); v += 7) fixed[v] = 0;
  const ContactProjector projector(P, N, {}, h, o);
  Mesh few = coarse, full = coarse;
  projector.project(few, &fixed);
  const detail::VertexTriangles every(coarse);
  projector.project(full, &fixed, every);
  EXPECT_EQ(few.vertices, full.vertices);
  EXPECT_NE(few.vertices, coarse.vertices);
  const detail::VertexTriangles some(coarse, &fixed);
  for (std::size_t v = 0; v < fixed.size(); ++v) {
    const auto first = every.triangles.begin() + every.offsets[v],
               last = every.triangles.begin() + every.offsets[v + 1];
    if (fixed[v]) {
      EXPECT_EQ(some.offsets[v], some.offsets[v + 1]);
    } else {
      EXPECT_TRUE(std::equal(first, last, some.triangles.begin() + some.offsets[v],
                             some.triangles.begin() + some.offsets[v + 1]));
    }
  }
  const detail::VertexTriangles other(
      marching_cubes(sample_grid(*make_builtin_shape("sphere"), 16, Bounds{})));
  EXPECT_THROW(projector.project(full, &fixed, other), Error);
}

TEST(ContactProjection, RejectsBadInput) {
  Mesh m = flat_patch(3, kSpacing, 0);
  PointMatrix P, N;
  add_plane_points(P, N, 100, kSpacing, 0, 1, 8);
  const PointMatrix fewer_normals = N.topRows(50);
  EXPECT_THROW(project_to_contact_points(m, P, fewer_normals, {}, kSpacing), Error);
  EXPECT_THROW(project_to_contact_points(m, P, N, Eigen::VectorXd::Ones(3), kSpacing), Error);
  EXPECT_THROW(project_to_contact_points(m, P, N, {}, 0.0), Error);
  PointMatrix bad = P;
  bad(0, 0) = std::nan("");
  EXPECT_THROW(project_to_contact_points(m, bad, N, {}, kSpacing), Error);
  for (const auto& change : std::vector<void (*)(ContactProjectionOptions&)>{
           [](ContactProjectionOptions& o) { o.radius = 0; },
           [](ContactProjectionOptions& o) { o.max_move = -1; },
           [](ContactProjectionOptions& o) { o.normal_agreement = 2; },
           [](ContactProjectionOptions& o) { o.min_points = 5; },
           [](ContactProjectionOptions& o) { o.depth_scale = std::nan(""); },
           [](ContactProjectionOptions& o) { o.max_variance_factor = 0.5; },
           [](ContactProjectionOptions& o) { o.max_residual = -1; }}) {
    ContactProjectionOptions o;
    change(o);
    EXPECT_THROW(project_to_contact_points(m, P, N, {}, kSpacing, o), Error);
  }
}

TEST(ContactProjection, PointsWhoseNormalsDisagreeWithTheirPlaceLoseTheirPull) {
  // A face with a strip of points as GCP gives them next to an edge: 0.05 h inside the face,
  // their normals tilted 20 degrees (gradients blended across the medial axis). Weighed by how
  // far their normals turn from the fit's, the vertices stay on the face; weighed alike, the
  // strip pulls them inside (the built-in box at 32^3: 0.146 h at worst, 0.085 h now).
  const double h = kSpacing;
  PointMatrix P(0, 3), N(0, 3);
  add_plane_points(P, N, 4000, 4 * h, 0.0, 1.0, 3);
  const double tilt = 20 * std::acos(-1.0) / 180;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> along(-4 * h, 4 * h), across(0.2 * h, 0.9 * h);
  for (int i = 0; i < 800; ++i) {
    P.conservativeResize(P.rows() + 1, 3);
    N.conservativeResize(N.rows() + 1, 3);
    P.row(P.rows() - 1) << across(rng), along(rng), -0.05 * h;
    N.row(N.rows() - 1) << std::sin(tilt), 0, std::cos(tilt);
  }
  ContactProjectionOptions o = local_projection_options();
  o.chord_offset = false;
  const Mesh patch = flat_patch(5, h / 4, 0.02 * h);
  auto worst_height = [&](const ContactProjectionOptions& options) {
    Mesh m = patch;
    project_to_contact_points(m, P, N, {}, h, options);
    return m.vertices.col(2).cwiseAbs().maxCoeff() / h;
  };
  const double weighed = worst_height(o);
  o.normal_turn_scale = 0;
  const double alike = worst_height(o);
  EXPECT_LT(weighed, 0.005);      // measured: 0.0014 h
  EXPECT_GT(alike, 5 * weighed);  // measured: 0.040 h
}

// The vertex normals that each vertex sums from its own triangles (in parallel) are the serial
// sweep's, bit for bit, on a noisy mesh with a triangle that names one vertex twice.
TEST(ContactProjection, ParallelVertexNormalsAreTheSweepsBitForBit) {
  Mesh mesh = marching_cubes(sample_grid(*make_builtin_shape("torus"), 24, Bounds{}));
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    for (int a = 0; a < 3; ++a) mesh.vertices(v, a) += u(rng);
  mesh.triangles.conservativeResize(mesh.triangles.rows() + 1, 3);
  mesh.triangles.row(mesh.triangles.rows() - 1) << 0, 0, 5;
  const PointMatrix sweep = detail::vertex_normals(mesh);
  const PointMatrix parallel = detail::vertex_normals(mesh, detail::VertexTriangles(mesh));
  EXPECT_GT(sweep.rows(), 1000);
  EXPECT_TRUE(parallel == sweep);
}

namespace {

// Exact contact points of the crease z = slope |x| (a valley, slope > 0) or -slope |x| (a ridge)
// over [-extent, extent]^2, each with its facet's unit normal.
void crease_points(PointMatrix& P, PointMatrix& N, int count, double extent, double slope) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-extent, extent);
  P.resize(count, 3);
  N.resize(count, 3);
  for (int q = 0; q < count; ++q) {
    const double x = u(rng), y = u(rng), side = x < 0 ? -1.0 : 1.0;
    P.row(q) << x, y, slope * std::abs(x);
    N.row(q) = Eigen::RowVector3d(-slope * side, 0, 1).normalized();
  }
}

// The largest vertical miss of the crease among `m`'s vertices within `reach` of its middle.
double crease_miss(const Mesh& m, double slope, double reach) {
  double worst = 0;
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
    if (m.vertices.row(v).head(2).cwiseAbs().maxCoeff() <= reach)
      worst = std::max(worst, std::abs(m.vertices(v, 2) - slope * std::abs(m.vertices(v, 0))));
  return worst;
}

}  // namespace

TEST(ContactProjection, CreasePlanesPutVerticesOnACreaseThatTheQuadricRounds) {
  // Two facets meeting at 20 degrees, as a polyhedral mesh's SDF has them everywhere at fine
  // grids: the quadric rounds the crease off by hundredths of a spacing, the two planes follow
  // it, on a ridge and in a valley alike.
  for (const double slope : {-std::tan(10 * M_PI / 180), std::tan(10 * M_PI / 180)}) {
    PointMatrix P, N;
    crease_points(P, N, 6000, 6 * kSpacing, slope);
    ContactProjectionOptions o = local_projection_options();
    o.chord_offset = false;
    o.crease_planes = false;
    Mesh quadric = flat_patch(17, kSpacing / 4, 0.02 * kSpacing), planes = quadric;
    project_to_contact_points(quadric, P, N, {}, kSpacing, o);
    o.crease_planes = true;
    project_to_contact_points(planes, P, N, {}, kSpacing, o);
    const double reach = kSpacing;
    EXPECT_GT(crease_miss(quadric, slope, reach), 5e-3 * kSpacing) << slope;
    // (Exact where both facets have points in a vertex's fit; a spacing from the crease the few
    // points beyond it leave the quadric's fit, 4e-6 spacings off.)
    EXPECT_LT(crease_miss(planes, slope, reach), 1e-5 * kSpacing) << slope;
    EXPECT_LT(crease_miss(planes, slope, reach / 2), 1e-9 * kSpacing) << slope;
  }
}

TEST(ContactProjection, CreasePlanesLeaveASmoothSurfaceToTheQuadric) {
  // On the sphere the quadric leaves its points nearly exact, so no vertex takes two planes:
  // the same mesh to the last bit.
  const double h = 2.0 / 31;
  const Mesh mc = marching_cubes(sample_grid(*make_builtin_shape("sphere"), 32, Bounds{}));
  PointMatrix P, N;
  sphere_points(P, N, int(40 * 4 * M_PI * 0.36 / (h * h)));
  ContactProjectionOptions o = local_projection_options();
  o.crease_planes = false;
  Mesh quadric = mc, planes = mc;
  project_to_contact_points(quadric, P, N, {}, h, o);
  o.crease_planes = true;
  project_to_contact_points(planes, P, N, {}, h, o);
  EXPECT_EQ(quadric.vertices, planes.vertices);
}
