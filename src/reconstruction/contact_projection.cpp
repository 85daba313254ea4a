#include "sdfcontour/reconstruction/contact_projection.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "pipeline/uninitialised_allocator.h"
#include "pipeline/work_counter.h"
#include "reconstruction/carving_internal.h"
#include "reconstruction/mesh_geometry.h"
#include "reconstruction/point_cubes.h"

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

// z(x, y) = c . (1, x, y, x^2, xy, y^2): a vertex's neighbourhood as heights over its tangent
// plane, in spacings.
using Coefficients = Eigen::Matrix<double, 6, 1>;
struct FitRow {
  Coefficients row;
  double z, w;
  Eigen::Vector3d normal;  // the point's unit normal in the tangent frame (a, b, n)
};

// The squared chord between a point's unit normal and the unit normal of the quadric c where
// the point lies (the vertex's normal, (0, 0, 1), before the first fit): 2 (1 - cos t) for a turn
// t, which is t^2 to within 2% below 30 degrees and needs no arc cosine (the projection's
// largest cost when it took one per row and round).
double squared_turn_chord(const FitRow& f, const Coefficients* c) {
  if (!c) return 2 * (1 - f.normal[2]);
  const double x = f.row[1], y = f.row[2];
  const auto& q = *c;
  const double ga = -(q[1] + 2 * q[3] * x + q[4] * y), gb = -(q[2] + q[4] * x + 2 * q[5] * y);
  const double cosine =
      (ga * f.normal[0] + gb * f.normal[1] + f.normal[2]) / std::sqrt(ga * ga + gb * gb + 1);
  return 2 * (1 - std::clamp(cosine, -1.0, 1.0));
}

using Matrix6 = Eigen::Matrix<double, 6, 6>;

// A row's products that the normal equations sum: the quadric's terms (1, x, y, x^2, xy, y^2)
// multiply pairwise into the 15 monomials of degree <= 4 (kPairMonomial), then z times each term,
// then z^2. Made once per row, they are summed in each round as one vector: the 6 x 6 outer
// products per row and round were most of a fit's time.
constexpr int kMonomials = 15, kRowMoments = 24;  // 15 + 6 + 1, padded
using RowMoments = std::array<double, kRowMoments>;
// Per pair of terms (i, j): the monomial x^a y^b of their product, as its place in
// (1, x, y, x^2, xy, y^2, x^3, x^2 y, x y^2, y^3, x^4, x^3 y, x^2 y^2, x y^3, y^4).
constexpr int kPairMonomial[6][6] = {{0, 1, 2, 3, 4, 5},    {1, 3, 4, 6, 7, 8},
                                     {2, 4, 5, 7, 8, 9},    {3, 6, 7, 10, 11, 12},
                                     {4, 7, 8, 11, 12, 13}, {5, 8, 9, 12, 13, 14}};

RowMoments row_moments(const FitRow& f) {
  const double x = f.row[1], y = f.row[2], z = f.z;
  const double x2 = x * x, xy = x * y, y2 = y * y;
  return {1,      x,      y,       x2,      xy,      y2,      x2 * x,  x2 * y,
          x * y2, y2 * y, x2 * x2, x2 * xy, x2 * y2, xy * y2, y2 * y2, z,
          z * x,  z * y,  z * x2,  z * xy,  z * y2,  z * z,   0,       0};
}

// The weighted sums of the rows' moments (sum w m, m each row's), in the rows' order.
RowMoments weighted_moments(const RowMoments* m, const double* w, std::size_t rows) {
  RowMoments sum{};
  for (std::size_t i = 0; i < rows; ++i)
    for (int k = 0; k < kRowMoments; ++k) sum[std::size_t(k)] += w[i] * m[i][std::size_t(k)];
  return sum;
}

// The normal equations' (symmetric) matrix from the summed moments.
Matrix6 moment_matrix(const RowMoments& s) {
  Matrix6 M;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) M(i, j) = s[std::size_t(kPairMonomial[i][j])];
  return M;
}

// M (its lower triangle, symmetric positive semi-definite) factored; false where it is singular
// to within rounding (a pivot below 12 epsilon of its largest diagonal entry).
bool factor(const Matrix6& M, Eigen::LLT<Matrix6>& llt) {
  llt.compute(M);
  if (llt.info() != Eigen::Success) return false;
  const double largest = M.diagonal().maxCoeff();
  const auto L = llt.matrixLLT().diagonal();
  for (int i = 0; i < 6; ++i)
    if (!(L[i] * L[i] > 12 * std::numeric_limits<double>::epsilon() * largest)) return false;
  return true;
}

// (M^-1)_00 from its factor M = L L^T: |L^-1 e_0|^2, one forward substitution.
double inverse_00(const Eigen::LLT<Matrix6>& llt) {
  const Matrix6& L = llt.matrixLLT();
  double y[6], sum = 0;
  for (int i = 0; i < 6; ++i) {
    double t = i == 0 ? 1.0 : 0.0;
    for (int j = 0; j < i; ++j) t -= L(i, j) * y[j];
    y[i] = t / L(i, i);
    sum += y[i] * y[i];
  }
  return sum;
}

// 1 / (2 sin(normal_turn_scale / 2))^2, so that a turn's squared chord times it is about
// (turn / normal_turn_scale)^2; 0 where the turns weigh nothing.
double inverse_turn_chord2(const ContactProjectionOptions& o) {
  const double chord_scale = 2 * std::sin(o.normal_turn_scale * std::acos(-1.0) / 360);
  return o.normal_turn_scale > 0 ? 1 / (chord_scale * chord_scale) : 0;
}

// Weighted least squares, then robust_rounds refits with each row's weight divided by
// 1 + (its miss / robust_scale)^2; with normal_turn_scale, every fit also divides it by
// 1 + (its normal's turn from the fit's / normal_turn_scale)^2, the turn measured by its chord,
// from the vertex's normal in the first fit (the built-in box at 32^3: vertices next to its
// edges 0.146 h inside a face at worst without the turns, 0.085 h with them). False where the
// rows give no reliable height at the vertex: a rank-deficient or one-sided neighbourhood
// (max_variance_factor), or points too far from any quadric (max_residual). The first fit's
// spread is judged without the turns: where the surface curves within the radius, its points
// turn from the vertex's normal for good reason (a cylinder of radius 4 h: 19 degrees 1.4 h
// away), and the next fit gives them their weight back. `inv_chord_scale2`: inverse_turn_chord2(o).
bool fit_quadric(const std::vector<FitRow>& fit, const ContactProjectionOptions& o,
                 double inv_chord_scale2, Coefficients& c) {
  if (int(fit.size()) < o.min_points) return false;
  Eigen::LLT<Matrix6> llt;
  // Per row: its weight after the robust and the turn's divisions; the divisions go first, row
  // by row, apart from the sums (where each waited on the last: most of a fit's time).
  thread_local std::vector<double> turned_buffer, plain_buffer;
  thread_local std::vector<RowMoments> moments_buffer;
  turned_buffer.resize(fit.size());
  moments_buffer.resize(fit.size());
  // (Plain pointers: through the vectors, each row's store reloaded them from thread storage.)
  double* const turned = turned_buffer.data();
  RowMoments* const moments = moments_buffer.data();
  for (std::size_t i = 0; i < fit.size(); ++i) moments[i] = row_moments(fit[i]);
  const double inv_robust_scale = 1 / o.robust_scale;
  Coefficients rhs;
  for (int round = 0; round <= o.robust_rounds; ++round) {
    // (One division a row: the robust and the turn's divisors multiplied.)
    for (std::size_t i = 0; i < fit.size(); ++i) {
      const FitRow& f = fit[i];
      double divisor = 1;
      if (round > 0) {
        const double miss = (f.z - f.row.dot(c)) * inv_robust_scale;
        divisor = 1 + miss * miss;
      }
      if (inv_chord_scale2 > 0)
        divisor *= 1 + squared_turn_chord(f, round > 0 ? &c : nullptr) * inv_chord_scale2;
      turned[i] = f.w / divisor;
    }
    const RowMoments sums = weighted_moments(moments, turned, fit.size());
    const double weight_sum = sums[0], weighted_z2 = sums[kMonomials + 6];
    for (int k = 0; k < 6; ++k) rhs[k] = sums[std::size_t(kMonomials + k)];
    const Matrix6 M = moment_matrix(sums);
    if (round == 0 && inv_chord_scale2 > 0) {
      // The first round's spread, without the turns' divisions.
      plain_buffer.resize(fit.size());
      for (std::size_t i = 0; i < fit.size(); ++i) plain_buffer[i] = fit[i].w;
      const RowMoments plain = weighted_moments(moments, plain_buffer.data(), fit.size());
      Eigen::LLT<Matrix6> spread;
      if (!factor(moment_matrix(plain), spread) ||
          inverse_00(spread) * plain[0] > o.max_variance_factor)
        return false;
      if (!factor(M, llt)) return false;
    } else if (!factor(M, llt) || inverse_00(llt) * weight_sum > o.max_variance_factor) {
      return false;
    }
    c = llt.solve(rhs);
    // Sum w (z - row.c)^2 = sum w z^2 - c.rhs at the least-squares solution.
    if (round == 0 && o.max_residual > 0 &&
        weighted_z2 - c.dot(rhs) > o.max_residual * o.max_residual * weight_sum)
      return false;
  }
  return true;
}

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

// Per vertex, the sum over its triangles of e e^T over their three edges e (in spacings), and
// the number of triangles: a flat triangle with its corners on z(x, y) lies
// sum_e Q(e) / 12 above it on average, Q the quadric's quadratic part, so the vertex's chord
// offset is minus the mean of that over its triangles. Only for the vertices that move (not
// `fixed`): a split's second projection moves a fifth of them.
struct EdgeMoments {
  std::vector<int> slot;  // per vertex: its place in sum and triangles, -1 where fixed
  detail::Unwritten<Eigen::Matrix3d> sum;
  detail::Unwritten<int> triangles;
};
EdgeMoments edge_moments(const Mesh& mesh, const detail::VertexTriangles& around, double spacing,
                         const std::vector<char>* fixed) {
  EdgeMoments m;
  m.slot.resize(std::size_t(mesh.vertices.rows()));
  int moving = 0;
  for (std::size_t v = 0; v < m.slot.size(); ++v) m.slot[v] = fixed && (*fixed)[v] ? -1 : moving++;
  m.sum.resize(std::size_t(moving));
  m.triangles.resize(std::size_t(moving));
  // Each vertex sums its triangles in ascending order (the same bits as a sweep over them).
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
    const int s = m.slot[std::size_t(v)];
    if (s < 0) return;
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (int o = around.offsets[std::size_t(v)]; o < around.offsets[std::size_t(v) + 1]; ++o) {
      const int t = around.triangles[std::size_t(o)];
      Eigen::Matrix3d e2 = Eigen::Matrix3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = (mesh.vertices.row(mesh.triangles(t, (k + 1) % 3)) -
                                   mesh.vertices.row(mesh.triangles(t, k)))
                                      .transpose() /
                                  spacing;
        e2 += e * e.transpose();
      }
      sum += e2;
    }
    m.sum[std::size_t(s)] = sum;
    m.triangles[std::size_t(s)] =
        around.offsets[std::size_t(v) + 1] - around.offsets[std::size_t(v)];
  });
  return m;
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

ContactProjectionStats ContactProjector::project(Mesh& mesh, const std::vector<char>* fixed) const {
  if (!mesh.vertices.allFinite()) throw Error("projection: the mesh's vertices must be finite");
  if (fixed && fixed->size() != std::size_t(mesh.vertices.rows()))
    throw Error("projection: one fixed flag per vertex is needed");
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
  const detail::VertexTriangles around(mesh);
  const PointMatrix N = detail::vertex_normals(mesh, around);
  const EdgeMoments chords =
      o.chord_offset ? edge_moments(mesh, around, spacing, fixed) : EdgeMoments{};
  const double radii[2] = {o.radius * spacing, o.wide_radius * spacing};
  const long reaches[2] = {1, std::max(1L, long(std::ceil(radii[1] / cubes.cell())))};
  std::vector<double> height(std::size_t(mesh.vertices.rows()), 0.0);
  const double inv_chord_scale2 = inverse_turn_chord2(o);
  detail::WorkCounter fitted(o.progress, long(mesh.vertices.rows()));
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
    fitted.add();
    const Eigen::Vector3d n = N.row(v).transpose();
    if (n.squaredNorm() == 0 || (fixed && (*fixed)[std::size_t(v)])) return;
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
    if (!fit_quadric(fit, o, inv_chord_scale2, c)) {
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
      if (!fit_quadric(fit, o, inv_chord_scale2, c)) return;
    }
    double z0 = c[0];
    const bool crease = o.crease_planes && crease_height(fit, c, inv_chord_scale2, z0);
    const int slot = o.chord_offset && !crease ? chords.slot[std::size_t(v)] : -1;
    if (slot >= 0 && chords.triangles[std::size_t(slot)] > 0) {
      const Eigen::Matrix3d& m = chords.sum[std::size_t(slot)];
      const double q = c[3] * a.dot(m * a) + c[4] * a.dot(m * b) + c[5] * b.dot(m * b);
      z0 -= q / 12 / chords.triangles[std::size_t(slot)];
    }
    if (std::isfinite(z0) && std::abs(z0) <= o.max_move) height[std::size_t(v)] = z0 * spacing;
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
