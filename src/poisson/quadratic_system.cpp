#include "quadratic_system.h"

#include "bspline.h"
#include "deterministic_sum.h"

namespace sdfcontour::poisson {

namespace {

// out[c] = (untied stiffness row c) . (in through the ties), for the cells with rows. Each row
// reads the 125 cells within two, found by cursors on the 25 coefficient lines around its own.
void stiffness_product(const QuadraticSystem& S, const std::vector<double>& in,
                       std::vector<double>& out) {
  const QuadraticCells& C = *S.cells;
  const QuadraticIntegrals& I = *S.integrals;
  const double h = S.level->h;  // grad . grad over h^3 du: res^2 h^3 = h
  for_each_line(
      C.grid.lines, C.grid.keys, [&](long oi, long oj, std::size_t first, std::size_t last) {
        LineCursor column[25];
        double across[25], along[25];  // per (ox, oy): the x and y factors of the two kinds of term
        for (int t = 0; t < 25; ++t) {
          const long gi = oi + t % 5 - 2, gj = oj + t / 5 - 2;
          if (gi >= 0 && gj >= 0) column[t] = LineCursor(C.grid.keys, C.grid.lines.line(gi, gj));
          const std::size_t ox = std::size_t(t % 5), oy = std::size_t(t / 5);
          const auto &mx = I.mass[std::size_t(oi)], &my = I.mass[std::size_t(oj)];
          const auto &kx = I.stiffness[std::size_t(oi)], &ky = I.stiffness[std::size_t(oj)];
          across[t] = kx[ox] * my[oy] + mx[ox] * ky[oy];  // times mass along z
          along[t] = mx[ox] * my[oy];                     // times stiffness along z
        }
        for (std::size_t c = first; c < last; ++c) {
          if (!S.row[c]) continue;
          const long ok = long(C.grid.keys[c] & kKeyMask);
          const auto &mz = I.mass[std::size_t(ok)], &kz = I.stiffness[std::size_t(ok)];
          double sum = 0;
          for (int t = 0; t < 25; ++t) {
            const long gi = oi + t % 5 - 2, gj = oj + t / 5 - 2;
            if (gi < 0 || gj < 0) continue;
            double m = 0, k = 0;
            for (std::size_t oz = 0; oz < 5; ++oz) {
              const long gk = ok + long(oz) - 2;
              if (gk < 0) continue;
              const int n = column[t].find(pack(gi, gj, gk));
              if (n < 0) continue;
              const double x = C.value(in, std::size_t(n));
              m += mz[oz] * x;
              k += kz[oz] * x;
            }
            sum += across[t] * m + along[t] * k;
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
  // Screened cells by group (a counting sort, each group in key order).
  const std::size_t cells = screening > 0 ? runs.cells.size() : 0;
  std::vector<std::size_t> at(cells);
  for (std::size_t r = 0; r < cells; ++r)
    ++S.group_begin[std::size_t(group_of(runs.cell(L, r))) + 1];
  for (std::size_t g = 1; g < 28; ++g) S.group_begin[g] += S.group_begin[g - 1];
  {
    auto next = S.group_begin;
    for (std::size_t r = 0; r < cells; ++r) at[r] = next[std::size_t(group_of(runs.cell(L, r)))]++;
  }
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
  stiffness_product(S, in, out);
  // Screening, one group at a time: each point adds  w_p B_c(p) chi(p)  to its 27 cells' rows.
  for (std::size_t g = 0; g < 27; ++g)
    tbb::parallel_for(S.group_begin[g], S.group_begin[g + 1], [&](std::size_t r) {
      const auto& cells = S.screened_cells[r];
      double x[27], sum[27] = {};
      for (int q = 0; q < 27; ++q)
        x[q] = cells[std::size_t(q)] >= 0 ? C.value(in, std::size_t(cells[std::size_t(q)])) : 0.0;
      for_each_screened_point(S, r, [&](double weight, const double* w) {
        double chi = 0;
        for (int q = 0; q < 27; ++q) chi += w[q] * x[q];
        chi *= weight;
        for (int q = 0; q < 27; ++q) sum[q] += w[q] * chi;
      });
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
