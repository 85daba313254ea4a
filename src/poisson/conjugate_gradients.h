// Internal: Jacobi-preconditioned conjugate gradients on one depth's system.
#pragma once

#include <vector>

#include "octree.h"
#include "system.h"

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

/// Solves the system for the nodes with solved[v]; the other nodes keep their values in x, which
/// also holds the initial guess. Sums are chunked, so x does not depend on the thread count.
/// Takes the system by value: move it in, and its right-hand side becomes the residual's storage.
CgState conjugate_gradients(const OctreeLevel& L, const std::vector<char>& solved,
                            LevelSystem system, std::vector<double>& x, const CgOptions& options);

}  // namespace sdfcontour::poisson
