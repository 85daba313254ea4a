#include "reconstruction/poisson/bspline.h"

namespace sdfcontour::poisson {

TrilinearStiffness::TrilinearStiffness() {
  // Per axis: mass m = int phi_a phi_b, stiffness k = int phi_a' phi_b' on [0, 1].
  const double m[2][2] = {{1.0 / 3, 1.0 / 6}, {1.0 / 6, 1.0 / 3}}, k[2][2] = {{1, -1}, {-1, 1}};
  for (int a = 0; a < 8; ++a)
    for (int b = 0; b < 8; ++b) {
      const int ax = a & 1, ay = a >> 1 & 1, az = a >> 2 & 1, bx = b & 1, by = b >> 1 & 1,
                bz = b >> 2 & 1;
      entry[a][b] = k[ax][bx] * m[ay][by] * m[az][bz] + m[ax][bx] * k[ay][by] * m[az][bz] +
                    m[ax][bx] * m[ay][by] * k[az][bz];
    }
}

const TrilinearStiffness& trilinear_stiffness() {
  static const TrilinearStiffness stiffness;
  return stiffness;
}

double quadratic_bspline(double t) {
  t = std::abs(t);
  if (t < 0.5) return 0.75 - t * t;
  if (t < 1.5) return 0.5 * (1.5 - t) * (1.5 - t);
  return 0;
}

HatQuadraticIntegrals::HatQuadraticIntegrals(long res, int up)
    : value(std::size_t(res + 1)), slope(std::size_t(res + 1)) {
  const double h = 1.0 / double(res), width = double(1L << up);  // Q's cell side, in hat cells
  for (long i = 0; i <= res; ++i)
    for (int o = -2; o <= 1; ++o) {
      const double centre = (double((i >> up) + o) + 0.5) * width;
      double v = 0, s = 0;
      // On each unit interval the hat is linear and Q quadratic (its knots fall on the hat's):
      // Simpson's rule is exact.
      for (long m = std::max(0L, i - 1); m <= std::min(res - 1, i); ++m) {
        const double sign = m < i ? 1.0 : -1.0;  // d hat / du on (m, m + 1)
        double fv = 0, fs = 0;
        for (int q = 0; q < 3; ++q) {
          const double u = double(m) + 0.5 * q, wq = q == 1 ? 4.0 / 6 : 1.0 / 6;
          const double bq = quadratic_bspline((u - centre) / width);
          fv += wq * (1 - std::abs(u - double(i))) * bq;
          fs += wq * sign * bq;
        }
        v += fv * h;
        s += fs;
      }
      value[std::size_t(i)][std::size_t(o + 2)] = v;
      slope[std::size_t(i)][std::size_t(o + 2)] = s;
    }
}

}  // namespace sdfcontour::poisson
