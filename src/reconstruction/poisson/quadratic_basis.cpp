#include "reconstruction/poisson/quadratic_basis.h"

#include <cmath>

#include "reconstruction/poisson/bspline.h"

namespace sdfcontour::poisson {

double quadratic_bspline_slope(double t) {
  const double a = std::abs(t);
  if (a < 0.5) return -2 * t;
  if (a < 1.5) return t > 0 ? -(1.5 - a) : (1.5 - a);
  return 0;
}

QuadraticIntegrals::QuadraticIntegrals(long r)
    : res(r), mass(std::size_t(r + 2)), slope(std::size_t(r + 2)), stiffness(std::size_t(r + 2)) {
  // On each unit cell both B-splines are single quadratics (their knots are the cells' faces), so
  // three-point Gauss-Legendre integrates their products exactly.
  const double g = 0.5 * std::sqrt(0.6), node[3] = {0.5 - g, 0.5, 0.5 + g},
               weight[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
  for (long i = -1; i <= res; ++i)
    for (int o = -2; o <= 2; ++o) {
      const long j = i + o;
      double m = 0, s = 0, k = 0;
      if (j >= -1 && j <= res)
        for (long cell = std::max(0L, i - 1); cell <= std::min(res - 1, i + 1); ++cell)
          for (int q = 0; q < 3; ++q) {
            const double u = double(cell) + node[q];
            const double bi = quadratic_bspline(u - double(i) - 0.5),
                         bj = quadratic_bspline(u - double(j) - 0.5),
                         di = quadratic_bspline_slope(u - double(i) - 0.5),
                         dj = quadratic_bspline_slope(u - double(j) - 0.5);
            m += weight[q] * bi * bj;
            s += weight[q] * di * bj;
            k += weight[q] * di * dj;
          }
      mass[std::size_t(i + 1)][std::size_t(o + 2)] = m;
      slope[std::size_t(i + 1)][std::size_t(o + 2)] = s;
      stiffness[std::size_t(i + 1)][std::size_t(o + 2)] = k;
    }
}

QuadraticCells quadratic_cells(const OctreeLevel& L, PoissonBoundary boundary) {
  QuadraticCells C;
  // Offset keys: active cell c shifted by -1..1 per axis is key c + 0..2.
  C.grid.keys = shifted_union(L.cells, {0, 0, 0}, {2, 2, 2}, L.res + 1);
  C.grid.lines = LineIndex(C.grid.keys);
  tie_to_boundary(L, boundary, C);
  return C;
}

void tie_to_boundary(const OctreeLevel& L, PoissonBoundary boundary, QuadraticCells& C) {
  const std::size_t n = C.size();
  C.has_ties = false;
  C.mirror.resize(n);
  C.sign.resize(n);
  C.solved.assign(n, 0);
  const bool tied = boundary != PoissonBoundary::Free;
  const long res = L.res;
  for_each_line(C.grid.lines, C.grid.keys,
                [&](long oi, long oj, std::size_t first, std::size_t last) {
                  const long i = oi - 1, j = oj - 1;
                  LineCursor support[9];  // active cell lines (i + dx, j + dy)
                  bool line_in_domain[9];
                  for (int t = 0; t < 9; ++t) {
                    const long si = i + t % 3 - 1, sj = j + t / 3 - 1;
                    line_in_domain[t] = si >= 0 && sj >= 0 && si < res && sj < res;
                    if (line_in_domain[t])
                      support[t] = LineCursor(L.cells, L.cell_lines.line(si, sj));
                  }
                  for (std::size_t c = first; c < last; ++c) {
                    const long k = long(C.grid.keys[c] & kKeyMask) - 1;
                    const long u[3] = {i, j, k};
                    long m[3];
                    int outside = 0;
                    for (int a = 0; a < 3; ++a) {
                      m[a] = std::clamp(u[a], 0L, res - 1);
                      outside += m[a] != u[a];
                    }
                    if (tied && outside > 0) {
                      C.mirror[c] = C.grid.find(m[0], m[1], m[2]);
                      C.sign[c] = boundary == PoissonBoundary::Dirichlet && (outside & 1) ? -1 : 1;
                      continue;
                    }
                    C.mirror[c] = int(c);
                    C.sign[c] = 1;
                    bool complete = true;
                    for (int t = 0; t < 9 && complete; ++t)
                      if (line_in_domain[t])
                        for (long sk = std::max(k - 1, 0L); sk <= std::min(k + 1, res - 1); ++sk)
                          if (support[t].find(pack(i + t % 3 - 1, j + t / 3 - 1, sk)) < 0) {
                            complete = false;
                            break;
                          }
                    C.solved[c] = complete;
                  }
                });
  for (std::size_t c = 0; c < n && !C.has_ties; ++c) C.has_ties = C.mirror[c] != int(c);
}

void apply_ties(const QuadraticCells& C, std::vector<double>& x) {
  tbb::parallel_for(std::size_t(0), C.size(), [&](std::size_t c) {
    if (C.mirror[c] != int(c)) x[c] = C.sign[c] * x[std::size_t(C.mirror[c])];
  });
}

std::vector<double> prolong_coefficients(const QuadraticCells& coarse, const QuadraticCells& fine,
                                         const std::vector<double>& x) {
  std::vector<double> out = prolong_splines(coarse.grid, fine.grid, x);
  apply_ties(fine, out);
  return out;
}

void restrict_integrals(const QuadraticCells& coarse, const QuadraticCells& fine,
                        const std::vector<double>& fine_e, std::vector<double>& e) {
  // Fine offset index of child t (0..3) of coarse offset index K: 2K + t - 2; weights 1 3 3 1 / 4.
  constexpr double w[4] = {0.25, 0.75, 0.75, 0.25};
  for_each_line(coarse.grid.lines, coarse.grid.keys,
                [&](long I, long J, std::size_t first, std::size_t last) {
                  LineCursor column[16];
                  for (int t = 0; t < 16; ++t) {
                    const long fi = 2 * I + t % 4 - 2, fj = 2 * J + t / 4 - 2;
                    if (fi >= 0 && fj >= 0)
                      column[t] = LineCursor(fine.grid.keys, fine.grid.lines.line(fi, fj));
                  }
                  for (std::size_t c = first; c < last; ++c) {
                    const long K = long(coarse.grid.keys[c] & kKeyMask);
                    double sum = 0;
                    for (int t = 0; t < 16; ++t) {
                      const long fi = 2 * I + t % 4 - 2, fj = 2 * J + t / 4 - 2;
                      if (fi < 0 || fj < 0) continue;
                      for (int z = 0; z < 4; ++z) {
                        const long fk = 2 * K + z - 2;
                        if (fk < 0) continue;
                        const int f = column[t].find(pack(fi, fj, fk));
                        if (f >= 0) sum += w[t % 4] * w[t / 4] * w[z] * fine_e[std::size_t(f)];
                      }
                    }
                    e[c] += sum;
                  }
                });
}

void quadratic_divergence(const OctreeLevel& L, const QuadraticCells& C,
                          const QuadraticIntegrals& I, const CellGrid& grid,
                          const std::vector<Eigen::Vector3d>& W, std::vector<double>& out) {
  const double h2 = L.h * L.h;  // d/dx = res d/du, and dx dy dz = h^3 du dv dw
  for_each_line(
      C.grid.lines, C.grid.keys, [&](long oi, long oj, std::size_t first, std::size_t last) {
        StencilLines lines(grid, oi, oj);
        // Per line: the x and y factors of the x, y and z terms.
        double fx[25], fy[25], fz[25];
        const auto &mx = I.mass[std::size_t(oi)], &my = I.mass[std::size_t(oj)];
        const auto &sx = I.slope[std::size_t(oi)], &sy = I.slope[std::size_t(oj)];
        for (int l = 0; l < lines.count(); ++l) {
          const std::size_t ox = std::size_t(lines.offset(l) % 5),
                            oy = std::size_t(lines.offset(l) / 5);
          fx[l] = sx[ox] * my[oy];
          fy[l] = mx[ox] * sy[oy];
          fz[l] = mx[ox] * my[oy];
        }
        for (std::size_t c = first; c < last; ++c) {
          const long ok = long(C.grid.keys[c] & kKeyMask);
          const auto &mz = I.mass[std::size_t(ok)], &sz = I.slope[std::size_t(ok)];
          double sum = 0;
          for (int l = 0; l < lines.count(); ++l) {
            double along = 0, across = 0;  // W.z against slopes, W.x and W.y against masses along z
            lines.window(l, ok, [&](std::size_t oz, std::size_t s) {
              const Eigen::Vector3d& v = W[s];
              across += mz[oz] * (fx[l] * v.x() + fy[l] * v.y());
              along += sz[oz] * v.z();
            });
            sum += across + fz[l] * along;
          }
          out[c] += h2 * sum;
        }
      });
}

std::vector<double> node_values(const OctreeLevel& L, const QuadraticCells& C,
                                const std::vector<double>& x) {
  // At a node every B-spline but those of its 8 cells vanishes, and those are 1/2 per axis. The
  // offset key of the cell below node index i is i.
  std::vector<double> out(L.nodes.size());
  for_each_line(L.node_lines, L.nodes, [&](long i, long j, std::size_t first, std::size_t last) {
    LineCursor column[4];
    for (int t = 0; t < 4; ++t)
      column[t] = LineCursor(C.grid.keys, C.grid.lines.line(i + (t & 1), j + (t >> 1)));
    for (std::size_t v = first; v < last; ++v) {
      const long k = long(L.nodes[v] & kKeyMask);
      double sum = 0;
      for (int q = 0; q < 8; ++q) {
        const int c = column[q & 3].find(pack(i + (q & 1), j + (q >> 1 & 1), k + (q >> 2 & 1)));
        if (c >= 0) sum += x[std::size_t(c)];
      }
      out[v] = 0.125 * sum;
    }
  });
  return out;
}

double evaluate(const OctreeLevel& L, const QuadraticCells& C, const std::vector<double>& x,
                const std::array<long, 3>& cell, const Eigen::Vector3d& p) {
  std::array<double, 3> w[3];
  for (int a = 0; a < 3; ++a)
    w[a] = quadratic_weights(
        std::clamp(p[a] * double(L.res) - double(cell[std::size_t(a)]), 0.0, 1.0));
  double sum = 0;
  for (int q = 0; q < 27; ++q) {
    const int dx = q % 3, dy = q / 3 % 3, dz = q / 9;
    const int c = C.find(cell[0] + dx - 1, cell[1] + dy - 1, cell[2] + dz - 1);
    if (c >= 0)
      sum +=
          w[0][std::size_t(dx)] * w[1][std::size_t(dy)] * w[2][std::size_t(dz)] * x[std::size_t(c)];
  }
  return sum;
}

}  // namespace sdfcontour::poisson
