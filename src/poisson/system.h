// Internal: the screened Poisson system at one depth, over the nodes solved for there.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <utility>
#include <vector>

#include "normal_field.h"
#include "octree.h"
#include "points.h"

namespace sdfcontour::poisson {

/// Leaves trivial elements uninitialised on resize, so that a large array is first touched (its
/// pages faulted in and zeroed by the system) by the parallel loop that fills it, not serially.
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <class U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// Rows (27 slots, slot(dx, dy, dz)) and right-hand side of one depth's system. Inside the domain
/// and away from points a row is the constant stiffness stencil h K (`interior_row`); only nodes
/// on the domain's faces (truncated stencil) and corners of cells holding points (screening) store
/// their own row.
struct LevelSystem {
  std::array<double, 27> interior_row{};
  std::vector<int> row_of;  ///< per node: its own row, or -1 (the interior row, or not solved)
  std::vector<std::array<double, 27>, UninitialisedAllocator<std::array<double, 27>>> rows;
  std::vector<double> b;  ///< per node; 0 on nodes not solved for
  const double* row(std::size_t v) const {
    return row_of[v] >= 0 ? rows[std::size_t(row_of[v])].data() : interior_row.data();
  }
};

/// The normal field's part of one depth's right-hand side, -int grad phi_v . V, for the nodes
/// with solved[v] (0 elsewhere): V from coarser splats given on `grid`, plus `finer` (the finer
/// splats' part, NormalField::finer at this depth).
std::vector<double> splat_divergence(const OctreeLevel& L, const std::vector<char>& solved,
                                     const CellGrid& grid,
                                     const std::vector<Eigen::Vector3d>& coarser,
                                     const std::vector<double>& finer);

/// The same with the coarser splats given on the coarser depth's spline grid, prolonged a slab of
/// rows at a time: the finest depth's whole spline grid (holding every cell within two of an
/// active cell) is the largest array of a reconstruction, and never exists.
std::vector<double> splat_divergence_from_coarser(const OctreeLevel& L,
                                                  const std::vector<char>& solved,
                                                  const CellGrid& coarser_grid,
                                                  const std::vector<Eigen::Vector3d>& coarser,
                                                  const std::vector<double>& finer);

/// Completes the system for the nodes with solved[v]: rows  int grad phi_u . grad phi_v +
/// screening * sum_p phi_u(p) phi_v(p)  and  b += screening * sum_p phi_v(p) / 2, over the points
/// in `runs` (the cells holding points); screening = alpha * (mean area) * 2^d.
LevelSystem assemble_system(const OctreeLevel& L, const std::vector<char>& solved,
                            std::vector<double> b, const CellRuns& runs, double screening,
                            const std::vector<UnitPoint>& points, const MortonRuns& morton);

}  // namespace sdfcontour::poisson
