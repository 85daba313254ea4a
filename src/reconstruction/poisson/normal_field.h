// Internal: the normal field V splatted into quadratic B-splines at each point's depth, and its
// divergence against the trilinear hats (the right-hand side of the Poisson system).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "reconstruction/poisson/keys.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"

namespace sdfcontour::poisson {

constexpr long kAllRows = 1L << 40;

/// A set of depth-d cells with indices -1..res per axis (the ring just outside the domain holds
/// splat coefficients whose B-splines reach into it), keyed with a +1 offset.
struct CellGrid {
  std::vector<Key> keys;  ///< sorted, offset by +1 per axis
  LineIndex lines;
  int find(long i, long j, long k) const {
    if (i < -1 || j < -1 || k < -1) return -1;
    return lines.find(keys, pack(i + 1, j + 1, k + 1));
  }
};

/// The active cells of a level that hold points, with their runs of Morton positions.
struct CellRuns {
  std::vector<std::array<std::uint32_t, 3>> cells;  ///< (cell index, first, last)
  /// The cell's (i, j, k) of run r.
  std::array<long, 3> cell(const OctreeLevel& L, std::size_t r) const {
    return unpack(L.cells[cells[r][0]]);
  }
};
CellRuns cell_runs(const OctreeLevel& L, const MortonRuns& runs);

/// V = sum over depths d of quadratic B-splines of depth d with coefficients splat[d] on
/// splat_cells[d]: each point adds area * n * (its quadratic weights) / h_d^3 at its splat depth
/// (a unit-integral kernel). Only the cells a depth's splats touch are stored.
struct NormalField {
  std::vector<CellGrid> splat_cells;
  std::vector<std::vector<Eigen::Vector3d>> splat;
  /// finer[d][v] = int grad(phi_v) . (the part of V splatted at depth d or finer).
  std::vector<std::vector<double>> finer;
  /// Per depth, the cells holding points (kept for the screening terms).
  std::vector<CellRuns> runs;
};

/// The depth's cells within two cells of an active cell: every spline coefficient the solve at
/// that depth reads, and every one that coarser ones prolong into exactly.
CellGrid spline_grid(const OctreeLevel& L);
/// The cells of spline_grid(L) whose first index lies in [first, last].
CellGrid spline_grid(const OctreeLevel& L, long first, long last);

/// onto += the coefficients (cells, values) that lie in `grid`'s key range (onto is on `grid`),
/// where `grid` holds every one of those cells (a slab of rows of a grid holding them all).
void add_on_grid(const CellGrid& cells, const std::vector<Eigen::Vector3d>& values,
                 const CellGrid& grid, std::vector<Eigen::Vector3d>& onto);

/// Splats the normals and computes the finer-splat divergence at every depth.
/// `cancel` (optional) is checked at each depth (throws Cancelled).
/// Without `hat_divergence` (degree 2) the finer-splat divergence against the hats is left empty.
NormalField splat_normals(const Octree& tree, const std::vector<UnitPoint>& points,
                          const MortonRuns& runs, const std::atomic<bool>* cancel = nullptr,
                          bool hat_divergence = true);

/// Quadratic B-spline coefficients on a finer grid from a coarser one's (exact where the finer
/// grid holds every cell the coarser coefficients reach).
/// T is Eigen::Vector3d (the normal field) or double (degree-2 coefficients).
template <class T>
std::vector<T> prolong_splines(const CellGrid& coarse, const CellGrid& fine,
                               const std::vector<T>& values);

/// out[v] += int grad(phi_v) . W for the nodes v of L with `want` unset or want[v] set and first
/// index in [rows[0], rows[1]), W given by the quadratic coefficients on `grid` of the depth `up`
/// (0 or 1) coarser than L's. The grid needs the cells with first index in
/// [(rows[0] >> up) - 2, ((rows[1] - 1) >> up) + 1].
void divergence(const OctreeLevel& L, const CellGrid& grid, const std::vector<Eigen::Vector3d>& W,
                std::vector<double>& out, const std::vector<char>* want,
                std::array<long, 2> rows = {0, kAllRows}, int up = 0);

}  // namespace sdfcontour::poisson
