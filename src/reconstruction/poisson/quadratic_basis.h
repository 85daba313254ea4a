// Internal: degree-2 elements. At depth d, chi is a sum of quadratic B-splines B_c centred on the
// centres of cells c, indices -1..res per axis (the ring just outside the domain holds the
// B-splines that reach into it). The boundary enters as ties: Neumann (even reflection) makes a
// ring coefficient equal to its mirror's inside the domain, Dirichlet (odd) its negative, so chi's
// normal derivative, resp. its value, is zero on the faces; free leaves every B-spline meeting the
// domain unmodified and independent. Integrals are cut at the domain's faces.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "reconstruction/poisson/normal_field.h"
#include "reconstruction/poisson/octree.h"
#include "sdfcontour/reconstruction/poisson.h"

namespace sdfcontour::poisson {

/// 1D integrals over the domain of one depth's B-splines, in cell units (u = x res): for index i in
/// -1..res and offset o in -2..2, at [i + 1][o + 2]:
///   mass = int B_i B_{i+o},  slope = int B_i' B_{i+o},  stiffness = int B_i' B_{i+o}'.
/// Inside (i in 1..res - 2 and i + o too) they do not depend on i.
struct QuadraticIntegrals {
  long res = 0;
  std::vector<std::array<double, 5>> mass, slope, stiffness;
  explicit QuadraticIntegrals(long res);
};

/// B(t) and B'(t) of the quadratic B-spline centred at 0 with unit knot spacing.
double quadratic_bspline_slope(double t);

/// One depth's coefficients: the cells within one of an active cell (every B-spline that is nonzero
/// on an active cell), keyed with a +1 offset as CellGrid, and how each one is determined.
struct QuadraticCells {
  CellGrid grid;
  /// Per cell: its mirror (itself when untied) and the tie's sign: the coefficient is
  /// sign * x[mirror]. Only ring cells are tied (Neumann and Dirichlet).
  std::vector<int> mirror;
  std::vector<signed char> sign;
  /// Per cell: solved for at this depth (its B-spline's support inside the domain lies in active
  /// cells, so its row of the system is complete). Others hold the coarser depth's solution.
  std::vector<char> solved;
  bool has_ties = false;  ///< some cell is tied
  std::size_t size() const { return grid.keys.size(); }
  /// Index of cell (i, j, k) (each in -1..res), or -1.
  int find(long i, long j, long k) const { return grid.find(i, j, k); }
};

/// The (up to) 25 lines of a cell grid around line (oi, oj) (offset indices): lines (oi + ox - 2,
/// oj + oy - 2), ox and oy in 0..4, each with a cursor for rows visited in increasing k. Where a
/// line holds k - 2 .. k + 2 they are five consecutive entries (found with two comparisons);
/// elsewhere (the band's edge, the domain's faces) the ones it holds are walked.
class StencilLines {
 public:
  StencilLines(const CellGrid& grid, long oi, long oj) : keys_(grid.keys.data()) {
    for (int t = 0; t < 25; ++t) {
      const long gi = oi + t % 5 - 2, gj = oj + t / 5 - 2;
      if (gi < 0 || gj < 0) continue;
      const auto range = grid.lines.line(gi, gj);
      if (range[0] == range[1]) continue;
      at_[count_] = range[0];
      end_[count_] = range[1];
      prefix_[count_] = pack(gi, gj, 0);
      offset_[count_++] = t;
    }
  }
  int count() const { return count_; }
  /// ox + 5 oy of line l.
  int offset(int l) const { return offset_[l]; }
  /// f(oz, index) for each cell of line l at offset index ok + oz - 2, oz in 0..4.
  template <class F>
  void window(int l, long ok, F&& f) {
    const Key low = prefix_[l] + Key(std::max(ok - 2, 0L)), high = prefix_[l] + Key(ok + 2);
    std::uint32_t a = at_[l];
    while (a < end_[l] && keys_[a] < low) ++a;
    at_[l] = a;
    if (ok >= 2 && a + 4 < end_[l] && keys_[a] == low && keys_[a + 4] == high) {
      for (std::size_t oz = 0; oz < 5; ++oz) f(oz, std::size_t(a + oz));
      return;
    }
    for (; a < end_[l] && keys_[a] <= high; ++a)
      f(std::size_t(long(keys_[a] - prefix_[l]) - ok + 2), std::size_t(a));
  }

 private:
  const Key* keys_;
  int count_ = 0;
  int offset_[25];
  std::uint32_t at_[25], end_[25];
  Key prefix_[25];
};

/// The coefficient cells of L with the boundary's ties and the solved cells.
QuadraticCells quadratic_cells(const OctreeLevel& L, PoissonBoundary boundary);

/// Sets C's ties and solved cells (mirror, sign, solved, has_ties) for a boundary; the cells
/// themselves do not depend on it.
void tie_to_boundary(const OctreeLevel& L, PoissonBoundary boundary, QuadraticCells& C);

/// Sets every tied coefficient of x from its mirror.
void apply_ties(const QuadraticCells& C, std::vector<double>& x);

/// out (on C) = the fine-depth coefficients of the function whose coarse-depth coefficients are x
/// (on coarse; ties applied): B_c = (B_{2c-1} + 3 B_{2c} + 3 B_{2c+1} + B_{2c+2}) / 4 per axis.
std::vector<double> prolong_coefficients(const QuadraticCells& coarse, const QuadraticCells& fine,
                                         const std::vector<double>& x);

/// e[c] += sum over the fine cells f of c's refinement weights w_cf times fine_e[f]: integrals
/// against fine B-splines become integrals against the coarse ones they sum to.
void restrict_integrals(const QuadraticCells& coarse, const QuadraticCells& fine,
                        const std::vector<double>& fine_e, std::vector<double>& e);

/// out[c] += int grad(B_c) . W over the domain, W = sum_s W_s B_s with W on `grid` (cells of the
/// same depth), for every cell of C.
void quadratic_divergence(const OctreeLevel& L, const QuadraticCells& C,
                          const QuadraticIntegrals& I, const CellGrid& grid,
                          const std::vector<Eigen::Vector3d>& W, std::vector<double>& out);

/// chi at each node of L (corners of active cells), from coefficients x on C (ties applied).
std::vector<double> node_values(const OctreeLevel& L, const QuadraticCells& C,
                                const std::vector<double>& x);

/// chi at unit-cube point p in L's active cell `cell`, from coefficients x on C (ties applied).
double evaluate(const OctreeLevel& L, const QuadraticCells& C, const std::vector<double>& x,
                const std::array<long, 3>& cell, const Eigen::Vector3d& p);

}  // namespace sdfcontour::poisson
