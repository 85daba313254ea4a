// Internal: the screened Poisson system of degree-2 elements at one depth.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "reconstruction/poisson/normal_field.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"
#include "reconstruction/poisson/quadratic_basis.h"

namespace sdfcontour::poisson {

/// Over the coefficient cells C: the stiffness  int grad B_u . grad B_v  plus
/// screening * sum_p w_p B_u(p) B_v(p), both through the ties (a tied ring cell's row and column
/// fold into its mirror's), and the right-hand side. The stiffness is applied from the 1D tables
/// (a 5 x 5 x 5 stencil); the screening is kept per point as its 3 x 3 per-axis weights.
struct QuadraticSystem {
  const OctreeLevel* level = nullptr;
  const QuadraticCells* cells = nullptr;
  const QuadraticIntegrals* integrals = nullptr;
  double screening = 0;
  /// Per cell: its row is computed (solved, or tied to a solved mirror).
  std::vector<char> row;
  /// Tied cells with rows, in index order: their rows fold into their mirrors'.
  std::vector<std::uint32_t> ring;
  /// Active cells holding points, grouped by (i mod 3, j mod 3, k mod 3): two cells of one group
  /// share no coefficient. Group g is [group_begin[g], group_begin[g + 1]).
  std::array<std::size_t, 28> group_begin{};
  std::vector<std::array<int, 27>> screened_cells;  ///< their 27 coefficients (-1: none)
  std::vector<std::uint32_t> point_begin;           ///< their points' range in screened_points
  struct ScreenedPoint {
    std::array<double, 9> axis_weight;  ///< per axis, cells -1, 0, +1
    double weight;
  };
  std::vector<ScreenedPoint> screened_points;
  std::vector<double> diagonal;  ///< per cell: the untied diagonal (the preconditioner's)
  std::vector<double> b;         ///< per cell; 0 where not solved
  /// The stiffness product's partial sums (kept between products: no page faults per product).
  mutable std::array<std::vector<double>, 4> scratch;
};

/// Completes the system: b = -divergence (int grad B_c . V per cell, untied) plus the screening's
/// screening * sum_p w_p B_c(p) / 2, folded through the ties; screening = alpha * (mean area) *
/// 2^d.
QuadraticSystem assemble_quadratic_system(const OctreeLevel& L, const QuadraticCells& C,
                                          const QuadraticIntegrals& I,
                                          std::vector<double> divergence, const CellRuns& runs,
                                          double screening, const std::vector<UnitPoint>& points,
                                          const MortonRuns& morton);

/// out = A in on the solved cells (0 elsewhere); returns in . out over them. `in` is read through
/// the ties and may be nonzero on fixed cells. Sums run in a fixed order whatever the threads.
double multiply(const QuadraticSystem& S, const std::vector<double>& in, std::vector<double>& out);

}  // namespace sdfcontour::poisson
