#include "reconstruction/poisson/quadratic_system.h"

#include "reconstruction/poisson/bspline.h"
#include "reconstruction/poisson/deterministic_sum.h"
#include "reconstruction/poisson/system.h"

namespace sdfcontour::poisson {

namespace {

// out[c] = (untied stiffness row c) . x for the cells with rows; x holds the coefficients with the
// ties applied. The stiffness is h (Kx My Mz + Mx Ky Mz + Mx My Kz) with 1D factors, so it is
// applied one axis at a time (sum factorisation, 35 products a row instead of 250): along z
// a = Mz x and b = Kz x, along y p = My a and q = Ky a + My b, along x out = h (Kx p + Mx q). Each
// pass is exact wherever a row reads it: a row's 125 neighbours exist, and so do those of the
// partial sums it reads (they lie on its own height k, in its 5 x 5 lines).
void stiffness_product(const QuadraticSystem& S, const double* x, std::vector<double>& out) {
  const QuadraticCells& C = *S.cells;
  const QuadraticIntegrals& I = *S.integrals;
  const std::size_t n = C.size();
  const Key* keys = C.grid.keys.data();
  auto& [a, b, p, q] = S.scratch;
  for (auto* v : {&a, &b, &p, &q}) v->resize(n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t c) {
    const auto &mz = I.mass[std::size_t(keys[c] & kKeyMask)],
               &kz = I.stiffness[std::size_t(keys[c] & kKeyMask)];
    double m = 0, k = 0;
    for (std::size_t oz = 0; oz < 5; ++oz) {
      const long at = long(c) + long(oz) - 2;  // the same line's neighbours are adjacent entries
      if (at < 0 || at >= long(n) || keys[at] != keys[c] + oz - 2) continue;
      m += mz[oz] * x[at];
      k += kz[oz] * x[at];
    }
    a[c] = m;
    b[c] = k;
  });
  for_each_line(C.grid.lines, C.grid.keys,
                [&](long oi, long oj, std::size_t first, std::size_t last) {
                  LineCursor column[5];
                  for (int oy = 0; oy < 5; ++oy)
                    if (oj + oy - 2 >= 0)
                      column[oy] = LineCursor(C.grid.keys, C.grid.lines.line(oi, oj + oy - 2));
                  const auto &my = I.mass[std::size_t(oj)], &ky = I.stiffness[std::size_t(oj)];
                  for (std::size_t c = first; c < last; ++c) {
                    const long k = long(keys[c] & kKeyMask);
                    double pm = 0, qm = 0;
                    for (std::size_t oy = 0; oy < 5; ++oy) {
                      if (oj + long(oy) - 2 < 0) continue;
                      const int at = column[oy].find(pack(oi, oj + long(oy) - 2, k));
                      if (at < 0) continue;
                      pm += my[oy] * a[std::size_t(at)];
                      qm += ky[oy] * a[std::size_t(at)] + my[oy] * b[std::size_t(at)];
                    }
                    p[c] = pm;
                    q[c] = qm;
                  }
                });
  const double h = S.level->h;  // grad . grad over h^3 du: res^2 h^3 = h
  for_each_line(C.grid.lines, C.grid.keys,
                [&](long oi, long oj, std::size_t first, std::size_t last) {
                  LineCursor column[5];
                  for (int ox = 0; ox < 5; ++ox)
                    if (oi + ox - 2 >= 0)
                      column[ox] = LineCursor(C.grid.keys, C.grid.lines.line(oi + ox - 2, oj));
                  const auto &mx = I.mass[std::size_t(oi)], &kx = I.stiffness[std::size_t(oi)];
                  for (std::size_t c = first; c < last; ++c) {
                    if (!S.row[c]) continue;
                    const long k = long(keys[c] & kKeyMask);
                    double sum = 0;
                    for (std::size_t ox = 0; ox < 5; ++ox) {
                      if (oi + long(ox) - 2 < 0) continue;
                      const int at = column[ox].find(pack(oi + long(ox) - 2, oj, k));
                      if (at >= 0) sum += kx[ox] * p[std::size_t(at)] + mx[ox] * q[std::size_t(at)];
                    }
                    out[c] = h * sum;
                  }
                });
}

// Calls f(cell, point, w) for every point of screened cell r with its 27 weights w.
template <class F>
void for_each_screened_point(const QuadraticSystem& S, std::size_t r, F&& f) {
  for (std::uint32_t q = S.point_begin[r]; q < S.point_begin[r + 1]; ++q) {
    const auto& a = S.screened_points[q].axis_weight;
    double w[27];
    for (int n = 0; n < 27; ++n)
      w[n] = a[std::size_t(n % 3)] * a[std::size_t(3 + n / 3 % 3)] * a[std::size_t(6 + n / 9)];
    f(S.screened_points[q].weight, w);
  }
}

// The ring's rows into their mirrors', in a fixed order; then 0 off the solved cells.
void fold_ties(const QuadraticSystem& S, std::vector<double>& out) {
  const QuadraticCells& C = *S.cells;
  for (const std::uint32_t r : S.ring) out[std::size_t(C.mirror[r])] += C.sign[r] * out[r];
  tbb::parallel_for(std::size_t(0), C.size(), [&](std::size_t c) {
    if (!C.solved[c]) out[c] = 0;
  });
}

int group_of(const std::array<long, 3>& c) {
  return int(c[0] % 3) + 3 * int(c[1] % 3) + 9 * int(c[2] % 3);
}

}  // namespace

QuadraticSystem assemble_quadratic_system(const OctreeLevel& L, const QuadraticCells& C,
                                          const QuadraticIntegrals& I,
                                          std::vector<double> divergence, const CellRuns& runs,
                                          double screening, const std::vector<UnitPoint>& points,
                                          const MortonRuns& morton) {
  QuadraticSystem S;
  S.level = &L;
  S.cells = &C;
  S.integrals = &I;
  S.screening = screening;
  const std::size_t n = C.size();
  S.row.assign(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const bool tied = C.mirror[c] != int(c);
    S.row[c] = C.solved[c] || (tied && C.solved[std::size_t(C.mirror[c])]);
    if (tied && S.row[c]) S.ring.push_back(std::uint32_t(c));
  }
  // Screened cells by group, each group in key order.
  const std::size_t cells = screening > 0 ? runs.cells.size() : 0;
  const std::vector<std::size_t> at = group_order<27>(
      cells, [&](std::size_t r) { return group_of(runs.cell(L, r)); }, S.group_begin);
  S.point_begin.assign(cells + 1, 0);
  for (std::size_t r = 0; r < cells; ++r)
    S.point_begin[at[r] + 1] = runs.cells[r][2] - runs.cells[r][1];
  for (std::size_t r = 0; r < cells; ++r) S.point_begin[r + 1] += S.point_begin[r];
  S.screened_cells.resize(cells);
  S.screened_points.resize(S.point_begin[cells]);
  tbb::parallel_for(std::size_t(0), cells, [&](std::size_t run) {
    const std::size_t r = at[run];
    const auto cell = runs.cell(L, run);
    for (int q = 0; q < 27; ++q)
      S.screened_cells[r][std::size_t(q)] =
          C.find(cell[0] + q % 3 - 1, cell[1] + q / 3 % 3 - 1, cell[2] + q / 9 - 1);
    auto* out = &S.screened_points[S.point_begin[r]];
    for (std::uint32_t q = runs.cells[run][1]; q < runs.cells[run][2]; ++q, ++out) {
      const UnitPoint& s = points[morton.point(q)];
      for (int a = 0; a < 3; ++a) {
        const double t =
            std::clamp(s.p[a] * double(L.res) - double(cell[std::size_t(a)]), 0.0, 1.0);
        const auto w = quadratic_weights(t);
        for (int m = 0; m < 3; ++m) out->axis_weight[std::size_t(3 * a + m)] = w[std::size_t(m)];
      }
      out->weight = s.weight;
    }
  });
  // Diagonal (untied) and right-hand side.
  S.diagonal.assign(n, 0.0);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t c) {
    if (!S.row[c]) return;
    const auto u = unpack(C.grid.keys[c]);
    const auto &mx = I.mass[std::size_t(u[0])], &my = I.mass[std::size_t(u[1])],
               &mz = I.mass[std::size_t(u[2])];
    const auto &kx = I.stiffness[std::size_t(u[0])], &ky = I.stiffness[std::size_t(u[1])],
               &kz = I.stiffness[std::size_t(u[2])];
    S.diagonal[c] = L.h * (kx[2] * my[2] * mz[2] + mx[2] * ky[2] * mz[2] + mx[2] * my[2] * kz[2]);
  });
  S.b = std::move(divergence);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t c) { S.b[c] = S.row[c] ? -S.b[c] : 0.0; });
  for (std::size_t g = 0; g < 27; ++g)
    tbb::parallel_for(S.group_begin[g], S.group_begin[g + 1], [&](std::size_t r) {
      double sum[27] = {}, square_sum[27] = {};
      for_each_screened_point(S, r, [&](double weight, const double* w) {
        for (int q = 0; q < 27; ++q) {
          sum[q] += weight * w[q];
          square_sum[q] += weight * w[q] * w[q];
        }
      });
      for (int q = 0; q < 27; ++q) {
        const int c = S.screened_cells[r][std::size_t(q)];
        if (c < 0 || !S.row[std::size_t(c)]) continue;
        S.b[std::size_t(c)] += screening * 0.5 * sum[q];
        S.diagonal[std::size_t(c)] += screening * square_sum[q];
      }
    });
  fold_ties(S, S.b);
  return S;
}

double multiply(const QuadraticSystem& S, const std::vector<double>& in, std::vector<double>& out) {
  const QuadraticCells& C = *S.cells;
  // The coefficients with the ties applied (a copy only where there are ties: the depths whose
  // active cells reach the domain's faces).
  std::vector<double> tied;
  if (C.has_ties) {
    tied = in;
    apply_ties(C, tied);
  }
  const std::vector<double>& x = C.has_ties ? tied : in;
  stiffness_product(S, x.data(), out);
  // Screening, one group at a time: each point adds  w_p B_c(p) chi(p)  to its 27 cells' rows.
  for (std::size_t g = 0; g < 27; ++g)
    tbb::parallel_for(S.group_begin[g], S.group_begin[g + 1], [&](std::size_t r) {
      const auto& cells = S.screened_cells[r];
      const std::vector<double>& xt = x;
      double x[27], sum[27] = {};
      for (int q = 0; q < 27; ++q)
        x[q] = cells[std::size_t(q)] >= 0 ? xt[std::size_t(cells[std::size_t(q)])] : 0.0;
      // chi(p) and the rows' terms one axis at a time (the weights are products of three).
      for (std::uint32_t q = S.point_begin[r]; q < S.point_begin[r + 1]; ++q) {
        const auto& a = S.screened_points[q].axis_weight;
        double chi = 0;
        for (int z = 0; z < 3; ++z) {
          double along_y = 0;
          for (int y = 0; y < 3; ++y) {
            const double* row = x + 3 * y + 9 * z;
            along_y += a[std::size_t(3 + y)] * (a[0] * row[0] + a[1] * row[1] + a[2] * row[2]);
          }
          chi += a[std::size_t(6 + z)] * along_y;
        }
        chi *= S.screened_points[q].weight;
        for (int z = 0; z < 3; ++z)
          for (int y = 0; y < 3; ++y) {
            const double yz = a[std::size_t(3 + y)] * a[std::size_t(6 + z)] * chi;
            double* row = sum + 3 * y + 9 * z;
            row[0] += a[0] * yz;
            row[1] += a[1] * yz;
            row[2] += a[2] * yz;
          }
      }
      for (int q = 0; q < 27; ++q) {
        const int c = cells[std::size_t(q)];
        if (c >= 0 && S.row[std::size_t(c)]) out[std::size_t(c)] += S.screening * sum[q];
      }
    });
  fold_ties(S, out);
  return deterministic_sum(C.size(),
                           [&](std::size_t c) { return C.solved[c] ? in[c] * out[c] : 0.0; });
}

}  // namespace sdfcontour::poisson
