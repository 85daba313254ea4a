// Internal: the screened Poisson system at one depth, over the nodes solved for there.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "pipeline/uninitialised_allocator.h"
#include "reconstruction/poisson/normal_field.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"

namespace sdfcontour::poisson {

using detail::UninitialisedAllocator;

/// The order of n items by group (group(r) in [0, G)), each group keeping the items' order (a
/// counting sort): item r goes to position at[r]; group g is [begin[g], begin[g + 1]).
template <std::size_t G, class Group>
std::vector<std::size_t> group_order(std::size_t n, Group&& group,
                                     std::array<std::size_t, G + 1>& begin) {
  std::vector<std::size_t> at(n);
  for (std::size_t r = 0; r < n; ++r) ++begin[std::size_t(group(r)) + 1];
  for (std::size_t g = 1; g <= G; ++g) begin[g] += begin[g - 1];
  auto next = begin;
  for (std::size_t r = 0; r < n; ++r) at[r] = next[std::size_t(group(r))]++;
  return at;
}

/// One depth's system: the stiffness  int grad phi_u . grad phi_v  plus the screening
/// screening * sum_p w_p phi_u(p) phi_v(p), and the right-hand side. Nothing is stored per row:
/// inside the domain the stiffness is the constant stencil h K (`interior_row`), on the domain's
/// faces its truncation (recomputed where used: few nodes), and the screening is kept per point,
/// as the trilinear weights of its cell's corners: a cell's 8 x 8 block is the sum of its points'
/// rank-one terms, and most cells hold one or two points (a block would take 36 doubles).
struct LevelSystem {
  std::array<double, 27> interior_row{};
  double screening = 0;
  /// Per cell holding points: its corner nodes (corner bits x=1, y=2, z=4) and its points,
  /// screened_points[point_begin[r], point_begin[r + 1]).
  /// The cells come grouped by the parity of (i, j, k): cells of one parity share no corner.
  /// Group g is [parity_begin[g], parity_begin[g + 1]).
  std::array<std::size_t, 9> parity_begin{};
  std::vector<std::array<int, 8>, UninitialisedAllocator<std::array<int, 8>>> screened_corners;
  std::vector<std::uint32_t, UninitialisedAllocator<std::uint32_t>> point_begin;
  /// Per point: its corners' trilinear weights and its weight (confidence).
  struct ScreenedPoint {
    std::array<double, 8> corner_weight;
    double weight;
  };
  std::vector<ScreenedPoint, UninitialisedAllocator<ScreenedPoint>> screened_points;
  /// Per node: its index in own_diagonal (a solved node on a face or a screened cell's corner),
  /// else -1 (its diagonal is interior_row's centre).
  std::vector<int> own_of;
  std::vector<double> own_diagonal;
  std::vector<double> b;  ///< per node; 0 on nodes not solved for
  double diagonal(std::size_t v) const {
    return own_of[v] >= 0 ? own_diagonal[std::size_t(own_of[v])] : interior_row[13];
  }
};

/// The normal field's part of one depth's right-hand side, -int grad phi_v . V, for the nodes
/// with solved[v] (0 elsewhere): V from coarser splats given on `grid`, plus `finer` (the finer
/// splats' part, NormalField::finer at this depth; its storage becomes the result's).
std::vector<double> splat_divergence(const OctreeLevel& L, const std::vector<char>& solved,
                                     const CellGrid& grid,
                                     const std::vector<Eigen::Vector3d>& coarser,
                                     std::vector<double> finer);

/// A depth between the coarser splats' grid and L, with its own splats (NormalField::splat_cells
/// and splat at that depth).
struct MiddleDepth {
  const OctreeLevel& level;
  const CellGrid& splat_cells;
  const std::vector<Eigen::Vector3d>& splat;
};

/// The same with the coarser splats given on the grid of the depth before L's, their divergence
/// taken against L's hats directly: the two finest depths' whole spline grids (holding every cell
/// within two of an active cell) and V on them are the largest arrays of a reconstruction, and
/// never exist. With `middle`, the coarser grid is two depths up: a slab of rows at a time, V is
/// prolonged onto the middle depth's cells, and the middle depth's splats added there.
std::vector<double> splat_divergence_from_coarser(const OctreeLevel& L,
                                                  const std::vector<char>& solved,
                                                  const CellGrid& coarser_grid,
                                                  const std::vector<Eigen::Vector3d>& coarser,
                                                  std::vector<double> finer,
                                                  const MiddleDepth* middle = nullptr);

/// Completes the system for the nodes with solved[v]: the screening blocks of the points in
/// `runs` (the cells holding points) and  b += screening * sum_p w_p phi_v(p) / 2;
/// screening = alpha * (mean area) * 2^d.
LevelSystem assemble_system(const OctreeLevel& L, const std::vector<char>& solved,
                            std::vector<double> b, const CellRuns& runs, double screening,
                            const std::vector<UnitPoint>& points, const MortonRuns& morton);

/// out = A in on the solved nodes (0 elsewhere); returns in . out over them. `in` may be nonzero
/// on fixed nodes (their values enter through the solved nodes' rows). Every sum runs in a fixed
/// order, so out does not depend on the thread count.
double multiply(const OctreeLevel& L, const std::vector<char>& solved, const LevelSystem& S,
                const std::vector<double>& in, std::vector<double>& out);

}  // namespace sdfcontour::poisson
