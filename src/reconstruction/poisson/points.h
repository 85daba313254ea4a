// Internal: the oriented points as the Poisson stages see them: checked, mapped into the unit
// cube, and sorted in Morton order so that at every depth a cell's points form one run.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "reconstruction/poisson/keys.h"
#include "sdfcontour/reconstruction/poisson.h"

namespace sdfcontour::poisson {

/// One oriented point in unit-cube coordinates.
struct UnitPoint {
  Eigen::Vector3d p;  ///< position in the unit cube
  Eigen::Vector3d n;  ///< unit normal
  double area = 0;    ///< surface area it stands for (unit-cube units), set from the density
  double weight = 1;  ///< confidence in (0, 1]: scales its normal and screening terms
  int depth = 0;      ///< the coarser of the two depths its normal is splatted at
  /// The share of its normal splatted at depth + 1, the rest at depth: its ideal depth's
  /// fractional part (Kazhdan et al. 2006, non-uniform samples), so the splat moves smoothly
  /// with the density instead of jumping a whole depth.
  double finer_share = 0;
};

/// The points mapped into the unit cube: unit = (p - centre) / size + 1/2.
struct UnitPoints {
  std::vector<UnitPoint> points;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double size = 1;  ///< the domain cube's side in the input's units
  Eigen::Vector3d to_unit(const Eigen::Vector3d& p) const {
    return (p - centre) / size + Eigen::Vector3d::Constant(0.5);
  }
  Eigen::Vector3d from_unit(const Eigen::Vector3d& u) const {
    return (u - Eigen::Vector3d::Constant(0.5)) * size + centre;
  }
};

/// Throws Error for options out of range, no points, a count mismatch, a non-finite coordinate or
/// normal, or a zero normal.
void validate(const OrientedPoints& input, const PoissonOptions& options);

/// Maps the points into the unit cube: the domain is their bounding cube enlarged by `scale`.
UnitPoints to_unit_cube(const OrientedPoints& input, double scale);

/// The points in Morton order of their cell at depth `depth`: at every coarser depth too, the
/// points of one cell are a contiguous run. Sums over points that run over cells and runs add in a
/// fixed order, whatever the thread count.
class MortonRuns {
 public:
  MortonRuns(const std::vector<UnitPoint>& points, int depth);
  /// Index (into the points) of the q-th point in Morton order.
  std::uint32_t point(std::size_t q) const { return order_[q].second; }
  std::size_t size() const { return order_.size(); }
  /// Calls f(cell, first, last) for each depth-`depth` cell holding points, in Morton order, with
  /// its run [first, last) of Morton positions.
  template <class F>
  void for_each_run(int depth, F&& f) const {
    const int shift = 3 * (depth_ - depth);
    for (std::size_t first = 0; first < order_.size();) {
      const Key code = order_[first].first >> shift;
      std::size_t last = first + 1;
      while (last < order_.size() && order_[last].first >> shift == code) ++last;
      f(morton_cell(code), first, last);
      first = last;
    }
  }

 private:
  int depth_;
  std::vector<std::pair<Key, std::uint32_t>> order_;
};

}  // namespace sdfcontour::poisson
