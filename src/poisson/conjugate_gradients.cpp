#include "conjugate_gradients.h"

#include <cmath>

#include "deterministic_sum.h"

namespace sdfcontour::poisson {

CgState conjugate_gradients(const OctreeLevel& L, const std::vector<char>& solved, LevelSystem S,
                            std::vector<double>& x, const CgOptions& o) {
  const std::size_t nn = L.nodes.size();
  // Jacobi preconditioner: z = r / diag, computed where used rather than stored.
  auto diag = [&](std::size_t v) {
    const double d = S.diagonal(v);
    return solved[v] && d > 0 ? d : 1.0;
  };
  const double b_norm = std::sqrt(
      deterministic_sum(nn, [&](std::size_t v) { return solved[v] ? S.b[v] * S.b[v] : 0.0; }));
  // The residual takes over the right-hand side's storage.
  std::vector<double> r = std::move(S.b), p(nn), Ap(nn);
  multiply(L, solved, S, x, Ap);
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
    const double pAp = multiply(L, solved, S, p, Ap);
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
