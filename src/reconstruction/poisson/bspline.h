// Internal: the B-spline elements of the Poisson solver. chi is trilinear (degree-1 B-splines,
// "hats" centred on nodes); the normal field is splatted with quadratic B-splines centred on cell
// centres. Coordinates are unit-cube units; at depth d a cell has side 1 / res, res = 2^d.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace sdfcontour::poisson {

/// Slot of offset (dx, dy, dz) in {-1, 0, 1}^3 among a node's 27 neighbours (or a cell's).
inline int slot(int dx, int dy, int dz) {
  return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1);
}

/// Trilinear weights of p in cell c at resolution res, corner bits x=1, y=2, z=4.
inline std::array<double, 8> corner_weights(const Eigen::Vector3d& p, const std::array<long, 3>& c,
                                            long res) {
  double t[3];
  for (int a = 0; a < 3; ++a)
    t[a] = std::clamp(p[a] * double(res) - double(c[std::size_t(a)]), 0.0, 1.0);
  std::array<double, 8> w;
  for (int k = 0; k < 8; ++k)
    w[std::size_t(k)] = ((k & 1) ? t[0] : 1 - t[0]) * ((k >> 1 & 1) ? t[1] : 1 - t[1]) *
                        ((k >> 2 & 1) ? t[2] : 1 - t[2]);
  return w;
}

/// The cell at resolution res holding unit-cube point p (clamped into the domain).
inline std::array<long, 3> cell_of(const Eigen::Vector3d& p, long res) {
  std::array<long, 3> c;
  for (int a = 0; a < 3; ++a)
    c[std::size_t(a)] = std::clamp(long(std::floor(p[a] * double(res))), 0L, res - 1);
  return c;
}

/// Stiffness matrix of the unit cube's trilinear basis (corner bits x=1, y=2, z=4): entry [a][b]
/// is int grad phi_a . grad phi_b over the unit cube; a cell of side h scales it by h.
struct TrilinearStiffness {
  double entry[8][8];
  TrilinearStiffness();
};
const TrilinearStiffness& trilinear_stiffness();

/// The quadratic B-spline centred at 0 with unit knot spacing (support [-1.5, 1.5]).
double quadratic_bspline(double t);

/// Weights of the quadratic B-splines of cells (m - 1, m, m + 1) at position t in [0, 1] of cell
/// m, per axis.
inline std::array<double, 3> quadratic_weights(double t) {
  return {0.5 * (1 - t) * (1 - t), 0.75 - (t - 0.5) * (t - 0.5), 0.5 * t * t};
}

/// 1D integrals over the domain [0, 1] between the hat of node i (res cells per axis) and the
/// quadratic B-spline Q of cell c = (i >> up) + o, o in -2..1, of the depth `up` (0 or 1) coarser:
/// value[i][o + 2] = int hat_i Q_c, slope[i][o + 2] = int hat_i' Q_c. Every Q reaching into
/// hat_i's support is among them. Near the domain's faces the integrals are cut there, so they
/// are tabulated for every node i in 0..res.
struct HatQuadraticIntegrals {
  std::vector<std::array<double, 4>> value, slope;
  explicit HatQuadraticIntegrals(long res, int up = 0);
};

}  // namespace sdfcontour::poisson
