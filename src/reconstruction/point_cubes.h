// Internal: points bucketed in cubes, for the points near a position (projection, adaptivity).
#pragma once

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "pipeline/uninitialised_allocator.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// The points bucketed in cubes of side `cell`, sorted by cube (x fastest): the points within a
// cell's reach of a position lie in nine runs of three consecutive cubes.
class PointCubes {
 public:
  // `anchored`: the cubes are those of the whole space's lattice of side `cell` (cube floor(p /
  // cell)), whatever the points' extent, so that any subset of the points (a brick's) meets the
  // same cubes and for_each_near's order (cube by cube, then point by point) is the same for it.
  PointCubes(const PointMatrix& P, double cell, bool anchored = false) : cell_(cell) {
    origin_ = P.colwise().minCoeff().transpose();
    const Eigen::Vector3d top = P.colwise().maxCoeff().transpose(), extent = top - origin_;
    // Keys must fit in 63 bits whatever the spread: coarser cubes only cost more tests.
    while ((extent / cell_).prod() > 1e17) cell_ *= 2;
    // (The space's cube indices must be exact integers in a double and fit a long.)
    anchored_ = anchored && cell_ == cell && (origin_.array().abs() / cell_ < 0x1p52).all() &&
                (top.array().abs() / cell_ < 0x1p52).all();
    for (int a = 0; a < 3; ++a) {
      if (anchored_) {
        first_[a] = long(std::floor(origin_[a] / cell_));
        size_[a] = long(std::floor(top[a] / cell_)) - first_[a] + 1;
      } else {
        size_[a] = long(extent[a] / cell_) + 1;
      }
    }
    keyed_.resize(std::size_t(P.rows()));
    tbb::parallel_for(Eigen::Index(0), P.rows(), [&](Eigen::Index i) {
      const auto c = cube_of(P.row(i).transpose());
      keyed_[std::size_t(i)] = {key(c[0], c[1], c[2]), int(i)};
    });
    tbb::parallel_sort(keyed_.begin(), keyed_.end());
    // Where each row of cubes (j, k) starts, so that a search reads its row alone: nine binary
    // searches over every point were most of a gather (not where the rows outnumber the points
    // many times over: the searches then stay whole).
    const long rows = size_[1] * size_[2];
    if (rows <= std::max(long(1) << 20, 4 * long(P.rows()))) {
      row_start_.assign(std::size_t(rows) + 1, int(keyed_.size()));
      for (std::size_t e = keyed_.size(); e-- > 0;)
        row_start_[std::size_t(keyed_[e].key / size_[0])] = int(e);
      for (long r = rows - 1; r >= 0; --r)
        row_start_[std::size_t(r)] =
            std::min(row_start_[std::size_t(r)], row_start_[std::size_t(r) + 1]);
    }
  }

  // The cubes' side (at least the one asked for).
  double cell() const { return cell_; }
  // Whether the cubes are the space's lattice's (asked for, and the points' spread allowed it).
  bool anchored() const { return anchored_; }

  // Calls f(point index) for every point in the 27 cubes around p (with `reach`, the
  // (2 reach + 1)^3 cubes: the points within reach sides of p).
  template <class F>
  void for_each_near(const Eigen::Vector3d& p, F&& f, long reach = 1) const {
    for_each_row(p, reach, [&](const Keyed* from, const Keyed* to) {
      for (const Keyed* e = from; e != to; ++e) f(e->point);
    });
  }

  // The points of P (the rows these cubes were built from) within squared distance r2 of p, among
  // for_each_near's cubes, written to buffer[0, count) in cube order; returns count and grows
  // buffer as needed. Branch-free per candidate: about half of them are kept, unpredictably.
  int collect_within(const PointMatrix& P, const Eigen::Vector3d& p, double r2, long reach,
                     std::vector<int>& buffer) const {
    int count = 0;
    for_each_row(p, reach, [&](const Keyed* from, const Keyed* to) {
      const std::size_t need = std::size_t(count) + std::size_t(to - from);
      if (buffer.size() < need) buffer.resize(std::max(need, 2 * buffer.size()));
      int* out = buffer.data();
      const double* rows = P.data();
      for (const Keyed* e = from; e != to; ++e) {
        const int i = e->point;
        const double dx = rows[3 * i] - p[0], dy = rows[3 * i + 1] - p[1],
                     dz = rows[3 * i + 2] - p[2];
        out[count] = i;
        count += (dx * dx + dy * dy) + dz * dz <= r2;
      }
    });
    return count;
  }

 private:
  // (A struct, not a std::pair, whose constructor would zero the list on one thread.)
  struct Keyed {
    long key;
    int point;
    bool operator<(const Keyed& o) const {
      return key < o.key || (key == o.key && point < o.point);
    }
  };

  // Calls f(from, to) with the entries of each row of cubes (j, k) within reach of p's cube, from
  // cube x0 to x1 of the row: the rows' start where it is kept, then binary searches.
  template <class F>
  void for_each_row(const Eigen::Vector3d& p, long reach, F&& f) const {
    const auto c = cube_of(p);
    const long x0 = std::max(0L, c[0] - reach), x1 = std::min(size_[0] - 1, c[0] + reach);
    for (long k = std::max(0L, c[2] - reach); k <= std::min(size_[2] - 1, c[2] + reach); ++k)
      for (long j = std::max(0L, c[1] - reach); j <= std::min(size_[1] - 1, c[1] + reach); ++j) {
        const Keyed *first = keyed_.data(), *last = keyed_.data() + keyed_.size();
        if (!row_start_.empty()) {
          const std::size_t row = std::size_t(k * size_[1] + j);
          first = keyed_.data() + row_start_[row];
          last = keyed_.data() + row_start_[row + 1];
        }
        const Keyed* from = std::lower_bound(first, last, Keyed{key(x0, j, k), -1});
        f(from, std::lower_bound(from, last, Keyed{key(x1 + 1, j, k), -1}));
      }
  }

  std::array<long, 3> cube_of(const Eigen::Vector3d& p) const {
    std::array<long, 3> c;
    for (int a = 0; a < 3; ++a) {
      const double at = anchored_ ? std::floor(p[a] / cell_) - double(first_[a])
                                  : std::floor((p[a] - origin_[a]) / cell_);
      c[std::size_t(a)] = long(std::clamp(at, -1.0, double(size_[a])));
    }
    return c;
  }
  long key(long i, long j, long k) const { return (k * size_[1] + j) * size_[0] + i; }

  double cell_;
  Eigen::Vector3d origin_;
  bool anchored_ = false;
  long first_[3] = {0, 0, 0};  // anchored: the first cube's lattice index
  long size_[3];
  Unwritten<Keyed> keyed_;      // (cube key, point), sorted
  std::vector<int> row_start_;  // per row j + k * size_[1], then the end; or empty
};

}  // namespace sdfcontour::detail
