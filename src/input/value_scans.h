// Internal: branch-free scans over a grid's values, for the whole-grid passes: row masks for those
// that then read the few samples near the surface (gradient norms, noise), extremes and counts
// (truncation). T: float or double.
#pragma once

#include <cstddef>

namespace sdfcontour::detail {

/// out[k] = 1 where row[k] (k in [from, to)) has a neighbour of the other sign (value < 0 or not)
/// at k - 1, k + 1 or `offset[0..3]` values away (the rows beside it), else 0.
template <class T>
void crossing_row(const T* row, const std::ptrdiff_t offset[4], int from, int to,
                  unsigned char* out);

/// out[k] = 1 where |row[k]| < near (k in [from, to)), else 0.
template <class T>
void near_row(const T* row, double near, int from, int to, unsigned char* out);

/// lo = min(lo, values), hi = max(hi, values) over n finite values.
template <class T>
void extremes(const T* values, std::size_t n, double& lo, double& hi);

/// Adds to `negatives` the values < 0, to `at_inside` those < 0 with -value >= inside, to
/// `at_outside` those > 0 with value >= outside (each value widened to double).
template <class T>
void count_beyond(const T* values, std::size_t n, double inside, double outside, long& negatives,
                  long& at_inside, long& at_outside);

}  // namespace sdfcontour::detail
