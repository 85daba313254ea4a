// Whole-grid passes in windows: over a file-mapped grid (GridView::drop_pages) each window's
// pages are dropped once the pass is done with them, so that checking and measuring a grid holds
// a window of it, not all of it (bunny 1024^3: 4.2 GB of mapped pages before the bricks began).
// Without a dropper a pass is one window: the plain parallel loop.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstddef>
#include <vector>

#include "sdfcontour/input/samples.h"

namespace sdfcontour::detail {

/// Values per window of a pass over n values: a 64th of them, at least 65,536 (a parallel
/// chunk) and at most 16 M (64 MB of float32).
inline std::size_t pass_window(std::size_t n) {
  return std::clamp(n / 64, std::size_t(1) << 16, std::size_t(1) << 24);
}

/// tbb::parallel_reduce(blocked_range(0, n, 1 << 16), identity, body, join) over `values`, one
/// window after another, the windows' results joined in order (so `join` must be exact, as
/// counts, minima and maxima are); the pass ends early once stop(result so far) holds.
template <class T, class V, class Body, class Join, class Stop>
V windowed_reduce(const std::function<void(const void*, std::size_t)>* drop_pages, const T* values,
                  std::size_t n, const V& identity, const Body& body, const Join& join,
                  const Stop& stop) {
  const std::size_t window = drop_pages ? pass_window(n) : std::max<std::size_t>(n, 1);
  V result = identity;
  for (std::size_t lo = 0; lo < n && !stop(result); lo += window) {
    const std::size_t hi = std::min(n, lo + window);
    result = join(result, tbb::parallel_reduce(tbb::blocked_range<std::size_t>(lo, hi, 1 << 16),
                                               identity, body, join));
    if (drop_pages) (*drop_pages)(values + lo, (hi - lo) * sizeof(T));
  }
  return result;
}

/// tbb::parallel_for(from, to, body) over the slabs i of `grid` (`values` its data), in windows
/// of whole slabs; after each window, the slabs before the next window's first less `lag` (those
/// a stencil of `lag` slabs no longer reads) are dropped.
template <class T, class Body>
void windowed_slabs(const GridView& grid, const T* values, int from, int to, int lag,
                    const Body& body) {
  const std::size_t plane = std::size_t(grid.dims[1]) * std::size_t(grid.dims[2]);
  const int step =
      grid.drop_pages ? std::max(1, int(pass_window(grid.size()) / std::max<std::size_t>(plane, 1)))
                      : std::max(1, to - from);
  int dropped = 0;  // slabs [0, dropped) are dropped
  for (int lo = from; lo < to; lo += step) {
    const int hi = std::min(to, lo + step);
    tbb::parallel_for(lo, hi, body);
    const int upto = hi < to ? hi - lag : grid.dims[0];
    if (grid.drop_pages && upto > dropped) {
      (*grid.drop_pages)(values + std::size_t(dropped) * plane,
                         std::size_t(upto - dropped) * plane * sizeof(T));
      dropped = upto;
    }
  }
}

/// The slabs' values in slab order, copied in parallel (a grid's crossings are millions of values:
/// copied one slab after another, they were a sixth of measuring bunny at 256^3 on two threads).
template <class T, class Part>
std::vector<T> concatenate(const std::vector<Part>& parts, std::vector<T> Part::*member) {
  std::vector<std::size_t> start(parts.size() + 1, 0);
  for (std::size_t s = 0; s < parts.size(); ++s)
    start[s + 1] = start[s] + (parts[s].*member).size();
  std::vector<T> out(start.back());
  tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t s) {
    std::copy((parts[s].*member).begin(), (parts[s].*member).end(), out.begin() + long(start[s]));
  });
  return out;
}

}  // namespace sdfcontour::detail
