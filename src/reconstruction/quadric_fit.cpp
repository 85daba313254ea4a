#include "reconstruction/quadric_fit.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace sdfcontour::detail {

namespace {

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

}  // namespace

double inverse_turn_chord2(const ContactProjectionOptions& o) {
  const double chord_scale = 2 * std::sin(o.normal_turn_scale * std::acos(-1.0) / 360);
  return o.normal_turn_scale > 0 ? 1 / (chord_scale * chord_scale) : 0;
}

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

}  // namespace sdfcontour::detail
