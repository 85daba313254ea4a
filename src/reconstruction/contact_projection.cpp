#include "sdfcontour/reconstruction/contact_projection.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "pipeline/work_counter.h"
#include "reconstruction/carving_internal.h"
#include "reconstruction/chord_offsets.h"
#include "reconstruction/mesh_geometry.h"
#include "reconstruction/point_cubes.h"
#include "reconstruction/quadric_fit.h"

namespace sdfcontour {

namespace {

void validate(const PointMatrix& points, const PointMatrix& normals, double spacing,
              const ContactProjectionOptions& o) {
  if (points.rows() != normals.rows())
    throw Error("projection: " + std::to_string(points.rows()) + " points but " +
                std::to_string(normals.rows()) + " normals");
  if (!points.allFinite() || !normals.allFinite())
    throw Error("projection: the points and normals must be finite");
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error("projection: the spacing must be positive and finite");
  if (!(o.radius > 0) || !std::isfinite(o.radius) || !(o.max_move >= 0) ||
      !std::isfinite(o.max_move) || !(o.normal_agreement >= -1 && o.normal_agreement <= 1) ||
      o.min_points < 6 || !(o.depth_scale >= 0) || !std::isfinite(o.depth_scale) ||
      !(o.max_variance_factor >= 1) || !(o.max_residual >= 0) || !std::isfinite(o.max_residual) ||
      o.robust_rounds < 0 || o.robust_rounds > 10 || !(o.robust_scale > 0) ||
      !std::isfinite(o.robust_scale) || !(o.wide_radius >= 0) || !std::isfinite(o.wide_radius))
    throw Error(
        "projection: radius must be positive, max_move non-negative, normal_agreement in [-1, 1], "
        "min_points at least 6 (a quadric has six coefficients), depth_scale non-negative, "
        "max_variance_factor at least 1, max_residual non-negative, robust_rounds in [0, 10], "
        "robust_scale positive and wide_radius non-negative");
}

using detail::Coefficients;
using detail::FitRow;

// Where the fitted points lie on one plane and their normals are its normal, both to within
// rounding (a flat face aligned with the grid: its points lie on lines, which leave the quadric
// undetermined), that plane's height at the vertex. Two lines always lie on a plane; their normals
// tell a flat from a curved surface or a step. False otherwise.
bool exact_plane_height(const std::vector<FitRow>& fit, double& z0) {
  constexpr double kFlatMiss = 1e-5;    // spacings: a float32 grid's rounding, far below any sag
  constexpr double kSameNormal = 1e-8;  // 1 - cosine: 0.008 degrees
  if (fit.size() < 3) return false;
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const FitRow& f : fit) {
    const Eigen::Vector3d r(1, f.row[1], f.row[2]);
    M += f.w * r * r.transpose();
    rhs += f.w * f.z * r;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(M);
  if (ldlt.info() != Eigen::Success ||
      !(ldlt.vectorD().minCoeff() > 1e-9 * M.diagonal().maxCoeff()))
    return false;  // the points on one line
  const Eigen::Vector3d p = ldlt.solve(rhs);
  const Eigen::Vector3d up = Eigen::Vector3d(-p[1], -p[2], 1).normalized();
  for (const FitRow& f : fit)
    if (!(std::abs(f.z - p[0] - p[1] * f.row[1] - p[2] * f.row[2]) <= kFlatMiss) ||
        !(f.normal.dot(up) >= 1 - kSameNormal))
      return false;
  z0 = p[0];
  return std::isfinite(z0);
}

// Where the fitted points lie on two planes that meet in a crease (between a polyhedron's facets,
// which a quadric rounds off; at fine grids most of a mesh's error lies within a spacing of its
// creases), the crease's height at the vertex: the lower plane's on a ridge, the higher's in a
// valley. The points go to the nearer in normal of the two normals furthest apart; each side's
// plane is the least-squares one through its points' heights (points on the crease line lie on
// both), each point weighing less by its normal's turn from its side's, as in the quadric's fit
// (blended normals next to an edge lie off both facets). Taken only where the
// quadric misses the points by more than kFlatMiss RMS, both sides have kMinSide points, the
// planes' weighted squared misses are under kBetter times the quadric's, and each side lies under
// the other's plane (a ridge) or over it (a valley). False otherwise.
bool crease_height(const std::vector<FitRow>& fit, const Coefficients& quadric,
                   double inv_chord_scale2, double& z0) {
  constexpr int kMinSide = 4;
  constexpr double kBetter = 0.25;
  constexpr double kFlatMiss = 1e-3;                   // spacings
  constexpr double kMinTurnChord2 = 2 * (1 - 0.9995);  // the sides' normals 1.8 degrees apart
  const std::size_t n = fit.size();
  if (n < 2 * kMinSide) return false;
  double quadric_miss = 0, weights = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const FitRow& f : fit) {
    const double miss = f.z - f.row.dot(quadric);
    quadric_miss += f.w * miss * miss;
    weights += f.w;
    mean += f.normal;
  }
  if (!(quadric_miss > kFlatMiss * kFlatMiss * weights)) return false;
  mean /= double(n);
  auto farthest = [&](const Eigen::Vector3d& from, double& distance2) {
    std::size_t best = 0;
    distance2 = -1;
    for (std::size_t i = 0; i < n; ++i)
      if ((fit[i].normal - from).squaredNorm() > distance2)
        distance2 = (fit[i].normal - from).squaredNorm(), best = i;
    return best;
  };
  double apart2;
  const Eigen::Vector3d na = fit[farthest(mean, apart2)].normal;
  const Eigen::Vector3d nb = fit[farthest(na, apart2)].normal;
  if (!(apart2 > kMinTurnChord2)) return false;
  // Both sides' moments (w, wx, wy, wxx, wxy, wyy, wz, wxz, wyz) in locals, each row adding to
  // one by a 0/1 factor: indexing the side's sums put every row's adds through memory.
  thread_local std::vector<char> side;
  side.resize(n);
  int count[2] = {0, 0};
  double m[2][9] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const FitRow& f = fit[i];
    const double to_a = f.normal.dot(na), to_b = f.normal.dot(nb);
    const bool on_b = to_b > to_a;
    side[i] = char(on_b);
    ++count[on_b];
    const double turn2 = 2 * (1 - std::min(1.0, on_b ? to_b : to_a));
    const double w = f.w / (1 + turn2 * inv_chord_scale2);
    const double w1 = on_b ? w : 0.0, w0 = w - w1;
    const double x = f.row[1], y = f.row[2];
    const double t[9] = {1, x, y, x * x, x * y, y * y, f.z, x * f.z, y * f.z};
    for (int k = 0; k < 9; ++k) {
      m[0][k] += w0 * t[k];
      m[1][k] += w1 * t[k];
    }
  }
  if (count[0] < kMinSide || count[1] < kMinSide) return false;
  Eigen::Vector3d plane[2];
  for (int s = 0; s < 2; ++s) {
    const double* q = m[s];
    Eigen::Matrix3d M;
    M << q[0], q[1], q[2], q[1], q[3], q[4], q[2], q[4], q[5];
    const Eigen::LLT<Eigen::Matrix3d> llt(M);
    if (llt.info() != Eigen::Success) return false;
    plane[s] = llt.solve(Eigen::Vector3d(q[6], q[7], q[8]));
    if (!plane[s].allFinite()) return false;
  }
  // Each row's miss of its own side's plane, and how far it lies below the other's (> 0 on a
  // ridge), in scalars: vectors made on the stack per row stalled the loop.
  double planes_miss = 0, under[2] = {0, 0};
  const double a0 = plane[0][0], a1 = plane[0][1], a2 = plane[0][2];
  const double b0 = plane[1][0], b1 = plane[1][1], b2 = plane[1][2];
  for (std::size_t i = 0; i < n; ++i) {
    const FitRow& f = fit[i];
    const double x = f.row[1], y = f.row[2];
    const double za = a0 + a1 * x + a2 * y, zb = b0 + b1 * x + b2 * y;
    const bool on_b = side[i];
    const double miss = f.z - (on_b ? zb : za);
    planes_miss += f.w * miss * miss;
    under[on_b] += f.w * ((on_b ? za : zb) - f.z);
  }
  if (!(planes_miss < kBetter * quadric_miss)) return false;
  if (under[0] > 0 && under[1] > 0)
    z0 = std::min(plane[0][0], plane[1][0]);
  else if (under[0] < 0 && under[1] < 0)
    z0 = std::max(plane[0][0], plane[1][0]);
  else
    return false;
  return true;
}

// Whether the fitted points lie on the quadric c to within kSmoothFitRms spacings, weighted RMS.
bool smooth_fit(const std::vector<FitRow>& fit, const Coefficients& c) {
  double weights = 0, misses = 0;
  for (const FitRow& f : fit) {
    const double miss = f.z - f.row.dot(c);
    weights += f.w;
    misses += f.w * miss * miss;
  }
  return misses < detail::kSmoothFitRms * detail::kSmoothFitRms * weights;
}

}  // namespace

ContactProjectionStats project_to_contact_points(Mesh& mesh, const PointMatrix& points,
                                                 const PointMatrix& normals,
                                                 const Eigen::VectorXd& depths, double spacing,
                                                 const ContactProjectionOptions& o,
                                                 const std::vector<char>* fixed) {
  return ContactProjector(points, normals, depths, spacing, o).project(mesh, fixed);
}

ContactProjector::ContactProjector(const PointMatrix& points, const PointMatrix& normals,
                                   const Eigen::VectorXd& depths, double spacing,
                                   const ContactProjectionOptions& o)
    : points_(points), normals_(normals), depths_(depths), spacing_(spacing), options_(o) {
  validate(points, normals, spacing, o);
  if (depths.size() != 0 && depths.size() != points.rows())
    throw Error("projection: " + std::to_string(points.rows()) + " points but " +
                std::to_string(depths.size()) + " depths");
  // Points within each radius, in cubes of the narrower (the wider reads more of them), the
  // space's own (anchored).
  if (points.rows() > 0)
    cubes_ = std::make_unique<detail::PointCubes>(points, o.radius * spacing, true);
}

ContactProjector::~ContactProjector() = default;

namespace {

void require_fixed_flags(const Mesh& mesh, const std::vector<char>* fixed) {
  if (fixed && fixed->size() != std::size_t(mesh.vertices.rows()))
    throw Error("projection: one fixed flag per vertex is needed");
}

}  // namespace

ContactProjectionStats ContactProjector::project(Mesh& mesh, const std::vector<char>* fixed,
                                                 detail::ChordOffsets* chords) const {
  require_fixed_flags(mesh, fixed);
  // Only the vertices it fits need their triangles (after a split, about 1% of them).
  return project(mesh, fixed, detail::VertexTriangles(mesh, fixed), chords);
}

ContactProjectionStats ContactProjector::project(Mesh& mesh, const std::vector<char>* fixed,
                                                 const detail::VertexTriangles& around,
                                                 detail::ChordOffsets* chords) const {
  if (!mesh.vertices.allFinite()) throw Error("projection: the mesh's vertices must be finite");
  require_fixed_flags(mesh, fixed);
  if (around.offsets.size() != std::size_t(mesh.vertices.rows()) + 1)
    throw Error("projection: the triangles around the vertices are another mesh's");
  const PointMatrix& points = points_;
  const PointMatrix& normals = normals_;
  const Eigen::VectorXd& depths = depths_;
  const double spacing = spacing_;
  const ContactProjectionOptions& o = options_;
  const double inv_depth_scale2 = depths.size() && o.depth_scale > 0
                                      ? 1 / (o.depth_scale * o.depth_scale * spacing * spacing)
                                      : 0;
  ContactProjectionStats stats;
  if (!cubes_ || mesh.vertices.rows() == 0) return stats;
  const detail::PointCubes& cubes = *cubes_;
  PointMatrix N(mesh.vertices.rows(), 3);  // the fitted vertices' rows only
  const detail::EdgeMoments edges(mesh, around, spacing);
  const double radii[2] = {o.radius * spacing, o.wide_radius * spacing};
  const long reaches[2] = {1, std::max(1L, long(std::ceil(radii[1] / cubes.cell())))};
  std::vector<double> height(std::size_t(mesh.vertices.rows()), 0.0);
  const double inv_chord_scale2 = detail::inverse_turn_chord2(o);
  if (chords && chords->size() != std::size_t(mesh.vertices.rows()))
    chords->resize(std::size_t(mesh.vertices.rows()));
  detail::WorkCounter fitted(o.progress, long(mesh.vertices.rows()));
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
    fitted.add();
    if (fixed && (*fixed)[std::size_t(v)]) return;
    N.row(v) = detail::unit_vertex_normal(mesh, around, v);
    const Eigen::Vector3d n = N.row(v).transpose();
    if (n.squaredNorm() == 0) return;
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    // A tangent frame (a, b, n); heights and offsets in spacings keep the system well scaled.
    const Eigen::Vector3d a =
        n.cross(std::abs(n[0]) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY())
            .normalized();
    const Eigen::Vector3d b = n.cross(a);
    // The agreeing points within radius r, Gaussian weights exp(-d^2 / (2 sigma^2)) with sigma =
    // r / sqrt(8), d in the tangent plane; summed in the order of the space's cubes, then of the
    // rows: the same bits for any brick's subset of the points, with no sort per vertex (where the
    // cubes could not be the space's, in row order).
    thread_local std::vector<int> near_buffer;
    thread_local std::vector<FitRow> fit_buffer;
    std::vector<int>& near = near_buffer;
    std::vector<FitRow>& fit = fit_buffer;
    auto gather = [&](double r, long reach) {
      const int count = cubes.collect_within(points, p, r * r, reach, near);
      if (!cubes.anchored()) std::sort(near.begin(), near.begin() + count);
      const double inv_two_sigma2 = 4.0 / (r * r);
      fit.clear();
      for (int e = 0; e < count; ++e) {
        const int i = near[std::size_t(e)];
        const Eigen::Vector3d d = points.row(i).transpose() - p;
        if (normals.row(i).dot(n.transpose()) <= o.normal_agreement) continue;
        const double xa = d.dot(a), ya = d.dot(b);
        double w = std::exp(-(xa * xa + ya * ya) * inv_two_sigma2);
        if (inv_depth_scale2 > 0) w /= 1 + depths[i] * depths[i] * inv_depth_scale2;
        const double x = xa / spacing, y = ya / spacing;
        const Eigen::Vector3d m = normals.row(i).transpose();
        FitRow f{Coefficients(), d.dot(n) / spacing, w,
                 Eigen::Vector3d(m.dot(a), m.dot(b), m.dot(n))};
        f.row << 1, x, y, x * x, x * y, y * y;
        fit.push_back(f);
      }
    };
    Coefficients c;
    gather(radii[0], reaches[0]);
    if (!detail::fit_quadric(fit, o, inv_chord_scale2, c)) {
      // Points on lines further apart than the radius (contact points of grid-aligned flats)
      // leave a quadric undetermined: a wider neighbourhood holds the next line. Too few points
      // that agree (an edge's vertex, whose normal neither face shares) would take the few
      // points between the faces wider (the box at 32^3: its vertices 0.012 h off on average,
      // 0.001 h without).
      if (!(o.wide_radius > 0) || int(fit.size()) < o.min_points) return;
      // An exact plane needs no wider fit, which would read what lies beyond the flat (the cube
      // at 64^3: the projection 1.91 -> 1.03 s).
      double flat = 0;
      if (exact_plane_height(fit, flat)) {
        if (std::abs(flat) <= o.max_move) height[std::size_t(v)] = flat * spacing;
        return;
      }
      gather(radii[1], reaches[1]);
      if (!detail::fit_quadric(fit, o, inv_chord_scale2, c)) return;
    }
    double z0 = c[0], offset = 0;
    const bool crease = o.crease_planes && crease_height(fit, c, inv_chord_scale2, z0);
    if (o.chord_offset && !crease && edges.triangles(v) > 0) {
      const Eigen::Matrix3d m = edges.sum(v);
      const double q = c[3] * a.dot(m * a) + c[4] * a.dot(m * b) + c[5] * b.dot(m * b);
      offset = -q / 12 / edges.triangles(v);
      z0 += offset;
    }
    if (!std::isfinite(z0) || !(std::abs(z0) <= o.max_move)) return;
    height[std::size_t(v)] = z0 * spacing;
    if (chords && offset != 0 && smooth_fit(fit, c)) {
      // The quadric's second-order part c3 x^2 + c4 xy + c5 y^2 over (a, b), as a form on edges.
      const Eigen::Matrix3d q = c[3] * a * a.transpose() +
                                c[4] / 2 * (a * b.transpose() + b * a.transpose()) +
                                c[5] * b * b.transpose();
      chords->offset[std::size_t(v)] = offset;
      chords->normal[std::size_t(v)] = n;
      chords->form[std::size_t(v)] = {q(0, 0), q(0, 1), q(0, 2), q(1, 1), q(1, 2), q(2, 2)};
    }
  });
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    const double z = height[std::size_t(v)];
    if (z == 0) continue;
    mesh.vertices.row(v) += z * N.row(v);
    ++stats.vertices_moved;
    stats.largest_move = std::max(stats.largest_move, std::abs(z));
  }
  return stats;
}

}  // namespace sdfcontour
