#include "reconstruction/triangle_cells.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace sdfcontour::detail {

CellGrid CellGrid::over(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double cell,
                        double most_columns) {
  CellGrid g;
  g.origin = lo;
  g.cell = cell;
  const Eigen::Vector3d extent = (hi - lo).cwiseMax(0.0);
  // (One cube where the extent or the cube is no finite length: every query reads it all.)
  if (!extent.allFinite() || !lo.allFinite() || !(cell > 0) || !std::isfinite(cell)) {
    g.origin = lo.allFinite() ? lo : Eigen::Vector3d::Zero();
    g.cell = INFINITY;
    return g;
  }
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
  tbb::parallel_for(std::size_t(0), ranges.size(),
                    [&](std::size_t b) { lowest_[b] = ranges[b].lo; });
  const double columns = double(grid_.n[0]) * double(grid_.n[1]);
  sparse_ = columns > std::max(double(1 << 22), 4.0 * double(ranges.size()));
  if (sparse_)
    place_sparse(ranges);
  else
    place_dense(ranges);
}

namespace {

template <class F>
void for_each_column(const TriangleCells::Range& r, int ny, F&& f) {
  for (int i = r.lo[0]; i <= r.hi[0]; ++i)
    for (int j = r.lo[1]; j <= r.hi[1]; ++j) f(std::size_t(i) * std::size_t(ny) + std::size_t(j));
}

}  // namespace

// The entries counted per column, then placed box by box at their column's next place (a
// counting sort, in parallel), then each column sorted by (k, box): the same lists in any order
// of placing.
void TriangleCells::place_dense(const std::vector<Range>& ranges) {
  const std::size_t columns = std::size_t(grid_.n[0]) * std::size_t(grid_.n[1]);
  std::vector<std::atomic<std::size_t>> next(columns);
  tbb::parallel_for(std::size_t(0), columns,
                    [&](std::size_t c) { next[c].store(0, std::memory_order_relaxed); });
  tbb::parallel_for(std::size_t(0), ranges.size(), [&](std::size_t b) {
    const Range& r = ranges[b];
    const std::size_t along = std::size_t(r.hi[2] - r.lo[2] + 1);
    for_each_column(r, grid_.n[1],
                    [&](std::size_t c) { next[c].fetch_add(along, std::memory_order_relaxed); });
  });
  column_start_.resize(columns + 1);
  column_start_[0] = 0;
  for (std::size_t c = 0; c < columns; ++c) {
    column_start_[c + 1] = column_start_[c] + next[c].load(std::memory_order_relaxed);
    next[c].store(column_start_[c], std::memory_order_relaxed);
  }
  entries_.resize(column_start_.back());
  tbb::parallel_for(std::size_t(0), ranges.size(), [&](std::size_t b) {
    const Range& r = ranges[b];
    const std::size_t along = std::size_t(r.hi[2] - r.lo[2] + 1);
    for_each_column(r, grid_.n[1], [&](std::size_t c) {
      std::size_t at = next[c].fetch_add(along, std::memory_order_relaxed);
      for (int k = r.lo[2]; k <= r.hi[2]; ++k) entries_[at++] = {k, int(b)};
    });
  });
  tbb::parallel_for(std::size_t(0), columns, [&](std::size_t c) {
    std::sort(entries_.begin() + std::ptrdiff_t(column_start_[c]),
              entries_.begin() + std::ptrdiff_t(column_start_[c + 1]));
  });
}

// Every (column, k, box) sorted, then the occupied columns and their entries.
void TriangleCells::place_sparse(const std::vector<Range>& ranges) {
  struct Keyed {
    std::size_t column;
    Entry entry;
    bool operator<(const Keyed& o) const {
      return column < o.column || (column == o.column && entry < o.entry);
    }
  };
  std::vector<std::size_t> offsets(ranges.size() + 1, 0);
  tbb::parallel_for(std::size_t(0), ranges.size(), [&](std::size_t b) {
    const Range& r = ranges[b];
    offsets[b + 1] = std::size_t(r.hi[0] - r.lo[0] + 1) * std::size_t(r.hi[1] - r.lo[1] + 1) *
                     std::size_t(r.hi[2] - r.lo[2] + 1);
  });
  for (std::size_t b = 0; b < ranges.size(); ++b) offsets[b + 1] += offsets[b];
  Unwritten<Keyed> keyed(offsets.back());
  tbb::parallel_for(std::size_t(0), ranges.size(), [&](std::size_t b) {
    std::size_t at = offsets[b];
    const Range& r = ranges[b];
    for_each_column(r, grid_.n[1], [&](std::size_t c) {
      for (int k = r.lo[2]; k <= r.hi[2]; ++k) keyed[at++] = {c, {k, int(b)}};
    });
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  entries_.resize(keyed.size());
  for (std::size_t e = 0; e < keyed.size(); ++e) {
    entries_[e] = keyed[e].entry;
    if (e == 0 || keyed[e].column != keyed[e - 1].column) {
      occupied_.push_back(keyed[e].column);
      column_start_.push_back(e);
    }
  }
  column_start_.push_back(keyed.size());
}

}  // namespace sdfcontour::detail
