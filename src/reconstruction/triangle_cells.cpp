#include "reconstruction/triangle_cells.h"

#include <tbb/parallel_for.h>

#include <numeric>

namespace sdfcontour::detail {

CellGrid CellGrid::over(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double cell,
                        double most_columns) {
  CellGrid g;
  g.origin = lo;
  g.cell = cell;
  const Eigen::Vector3d extent = (hi - lo).cwiseMax(0.0);
  for (;; g.cell *= 2) {
    const Eigen::Vector3d count = (extent / g.cell).array().floor() + 1;
    if (count.maxCoeff() < 0x1p30 && count[0] * count[1] <= most_columns) {
      for (int a = 0; a < 3; ++a) g.n[std::size_t(a)] = int(count[a]);
      return g;
    }
  }
}

TriangleCells::TriangleCells(const CellGrid& grid, const std::vector<Range>& ranges)
    : grid_(grid), lowest_(ranges.size()) {
  const std::size_t count = ranges.size();
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t b) { lowest_[b] = ranges[b].lo; });
  // The entries counted per column, then placed box by box (a counting sort: each column's boxes
  // ascending), then each column sorted by k.
  const std::size_t columns = std::size_t(grid_.n[0]) * std::size_t(grid_.n[1]);
  auto for_each_column = [&](const Range& r, auto&& f) {
    for (int i = r.lo[0]; i <= r.hi[0]; ++i)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j)
        f(std::size_t(i) * std::size_t(grid_.n[1]) + std::size_t(j));
  };
  column_start_.assign(columns + 1, 0);
  for (const Range& r : ranges)
    for_each_column(
        r, [&](std::size_t c) { column_start_[c + 1] += std::size_t(r.hi[2] - r.lo[2] + 1); });
  std::partial_sum(column_start_.begin(), column_start_.end(), column_start_.begin());
  entries_.resize(column_start_.back());
  std::vector<std::size_t> at(column_start_.begin(), column_start_.end() - 1);
  for (std::size_t b = 0; b < count; ++b)
    for_each_column(ranges[b], [&](std::size_t c) {
      for (int k = ranges[b].lo[2]; k <= ranges[b].hi[2]; ++k) entries_[at[c]++] = {k, int(b)};
    });
  tbb::parallel_for(std::size_t(0), columns, [&](std::size_t c) {
    std::sort(entries_.begin() + std::ptrdiff_t(column_start_[c]),
              entries_.begin() + std::ptrdiff_t(column_start_[c + 1]));
  });
}

}  // namespace sdfcontour::detail
