// Internal: Jacobi-preconditioned conjugate gradients on one depth's system.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "reconstruction/poisson/deterministic_sum.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/system.h"

namespace sdfcontour::poisson {

struct CgOptions {
  double tolerance = 1e-4;  ///< stop at this residual relative to |b|
  int max_iterations = 200;
  const std::atomic<bool>* cancel = nullptr;  ///< checked every iteration (throws Cancelled)
};

/// How the solve ended (as OpenVDB's pcg::State).
struct CgState {
  int iterations = 0;
  double relative_residual = 0;  ///< |b - A x| / |b| over the unknowns
  bool converged = false;        ///< the relative residual reached the tolerance
};

/// Solves A x = b for the unknowns v with solved[v] (v in [0, n)); the others keep their values in
/// x, which also holds the initial guess, and enter through the unknowns' rows.
///  - multiply(in, out): out = A in on the unknowns, 0 elsewhere; returns in . out over them.
///  - diagonal(v): A's diagonal at unknown v (the preconditioner; 1 is used where it is <= 0).
/// b becomes the residual's storage. Sums are chunked, so x does not depend on the thread count.
template <class Multiply, class Diagonal>
CgState conjugate_gradients(std::size_t n, const std::vector<char>& solved, std::vector<double> b,
                            Multiply&& multiply, Diagonal&& diagonal, std::vector<double>& x,
                            const CgOptions& o) {
  // Jacobi preconditioner: z = r / diag, computed where used rather than stored.
  auto diag = [&](std::size_t v) {
    const double d = diagonal(v);
    return solved[v] && d > 0 ? d : 1.0;
  };
  const double b_norm =
      std::sqrt(deterministic_sum(n, [&](std::size_t v) { return solved[v] ? b[v] * b[v] : 0.0; }));
  std::vector<double> r = std::move(b), p(n), Ap(n);
  multiply(x, Ap);
  for (std::size_t v = 0; v < n; ++v) {
    r[v] = solved[v] ? r[v] - Ap[v] : 0.0;
    p[v] = r[v] / diag(v);
  }
  double rz = deterministic_sum(n, [&](std::size_t v) { return r[v] * (r[v] / diag(v)); });
  double r_norm = std::sqrt(deterministic_sum(n, [&](std::size_t v) { return r[v] * r[v]; }));
  CgState state;
  const double target = o.tolerance * std::max(b_norm, 1e-300);
  // Each iteration makes three passes over the unknowns: the product (with p . Ap), the update
  // (with r . z and r . r) and the new direction.
  while (state.iterations < o.max_iterations && r_norm > target && rz > 0) {
    check_cancel(o.cancel);
    const double pAp = multiply(p, Ap);
    if (!(pAp > 0)) break;
    const double step = rz / pAp;
    const auto sums = deterministic_sums<2>(n, [&](std::size_t v, std::array<double, 2>& s) {
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
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t v) {
      p[v] = solved[v] ? r[v] / diag(v) + beta * p[v] : 0.0;
    });
    ++state.iterations;
  }
  state.relative_residual = r_norm / std::max(b_norm, 1e-300);
  state.converged = r_norm <= target;
  return state;
}

/// The trilinear system of one depth (system.h), for the nodes with solved[v]. Takes the system by
/// value: move it in, and its right-hand side becomes the residual's storage.
CgState conjugate_gradients(const OctreeLevel& L, const std::vector<char>& solved,
                            LevelSystem system, std::vector<double>& x, const CgOptions& options);

}  // namespace sdfcontour::poisson
