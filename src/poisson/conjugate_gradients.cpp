#include "conjugate_gradients.h"

#include <cmath>

#include "bspline.h"
#include "deterministic_sum.h"

namespace sdfcontour::poisson {

namespace {

// out = A in on the unknowns (0 elsewhere); returns in . out. The search direction is zero on
// fixed nodes, so products with it involve unknowns only. Every in-domain neighbour of an unknown
// node exists (its incident cells are active): (i + dx, j + dy, k + dz) sits at dz from
// (i + dx, j + dy, k), found by a cursor on that node line (no stored neighbour table: at depth
// 10 it would be 36 bytes per node).
double apply(const OctreeLevel& L, const std::vector<char>& solved, const LevelSystem& S,
             const std::vector<double>& in, std::vector<double>& out) {
  const double kCentre = S.interior_row[13], kEdge = S.interior_row[std::size_t(slot(1, 1, 0))],
               kCorner = S.interior_row[std::size_t(slot(1, 1, 1))];
  for_each_line(L.node_lines, L.nodes, [&](long i, long j, std::size_t first, std::size_t last) {
    LineCursor neighbours[9];
    for (int t = 0; t < 9; ++t)
      neighbours[t] = LineCursor(L.nodes, L.node_lines.line(i + t % 3 - 1, j + t / 3 - 1));
    int column[9];
    long previous_k = -2;  // of the last unknown node
    for (std::size_t v = first; v < last; ++v) {
      if (!solved[v]) {
        out[v] = 0;
        continue;
      }
      const long k = long(L.nodes[v] & kKeyMask);
      // Right after an unknown at k - 1, each neighbour is the node after that one's.
      if (k == previous_k + 1)
        for (int t = 0; t < 9; ++t) column[t] += column[t] >= 0;
      else
        for (int t = 0; t < 9; ++t)
          column[t] = neighbours[t].find(pack(i + t % 3 - 1, j + t / 3 - 1, k));
      previous_k = k;
      double sum = 0;
      if (S.row_of[v] < 0) {
        // Interior: all 27 neighbours exist, and the trilinear stiffness stencil is zero on the
        // six face neighbours, one value on the twelve edge and another on the eight corner
        // neighbours.
        const double* x = in.data();
        double edges = 0, corners = 0;
        for (int t : {0, 2, 6, 8}) {
          const int m = column[t];
          edges += x[m];
          corners += x[m - 1] + x[m + 1];
        }
        for (int t : {1, 3, 5, 7}) {
          const int m = column[t];
          edges += x[m - 1] + x[m + 1];
        }
        sum = kCentre * x[v] + kEdge * edges + kCorner * corners;
      } else {
        const double* row = S.row(v);
        for (int dz = k > 0 ? -1 : 0; dz <= (k < L.res ? 1 : 0); ++dz)
          for (int t = 0; t < 9; ++t)
            if (column[t] >= 0) sum += row[t + 9 * (dz + 1)] * in[std::size_t(column[t] + dz)];
      }
      out[v] = sum;
    }
  });
  return deterministic_sum(L.nodes.size(),
                           [&](std::size_t v) { return solved[v] ? in[v] * out[v] : 0.0; });
}

}  // namespace

CgState conjugate_gradients(const OctreeLevel& L, const std::vector<char>& solved, LevelSystem S,
                            std::vector<double>& x, const CgOptions& o) {
  const std::size_t nn = L.nodes.size();
  // Jacobi preconditioner: z = r / diag, computed where used rather than stored.
  auto diag = [&](std::size_t v) {
    const double d = S.row(v)[13];
    return solved[v] && d > 0 ? d : 1.0;
  };
  const double b_norm = std::sqrt(
      deterministic_sum(nn, [&](std::size_t v) { return solved[v] ? S.b[v] * S.b[v] : 0.0; }));
  // The residual takes over the right-hand side's storage.
  std::vector<double> r = std::move(S.b), p(nn), Ap(nn);
  apply(L, solved, S, x, Ap);
  for (std::size_t v = 0; v < nn; ++v) {
    r[v] = solved[v] ? r[v] - Ap[v] : 0.0;
    p[v] = r[v] / diag(v);
  }
  double rz = deterministic_sum(nn, [&](std::size_t v) { return r[v] * (r[v] / diag(v)); });
  double r_norm = std::sqrt(deterministic_sum(nn, [&](std::size_t v) { return r[v] * r[v]; }));
  CgState state;
  const double target = o.tolerance * std::max(b_norm, 1e-300);
  // Each iteration makes three passes over the nodes: the product (with p . Ap), the update (with
  // r . z and r . r) and the new direction.
  while (state.iterations < o.max_iterations && r_norm > target && rz > 0) {
    check_cancel(o.cancel);
    const double pAp = apply(L, solved, S, p, Ap);
    if (!(pAp > 0)) break;
    const double step = rz / pAp;
    const auto sums = deterministic_sums<2>(nn, [&](std::size_t v, std::array<double, 2>& s) {
      if (solved[v]) {
        x[v] += step * p[v];
        r[v] -= step * Ap[v];
      }
      s[0] += r[v] * (r[v] / diag(v));
      s[1] += r[v] * r[v];
    });
    const double beta = sums[0] / rz;
    rz = sums[0];
    r_norm = std::sqrt(sums[1]);
    tbb::parallel_for(std::size_t(0), nn, [&](std::size_t v) {
      p[v] = solved[v] ? r[v] / diag(v) + beta * p[v] : 0.0;
    });
    ++state.iterations;
  }
  state.relative_residual = r_norm / std::max(b_norm, 1e-300);
  state.converged = r_norm <= target;
  return state;
}

}  // namespace sdfcontour::poisson
