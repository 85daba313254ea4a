// Internal: branch-free scans over a grid's values, for the whole-grid passes: row masks for those
// that then read the few samples near the surface (gradient norms, noise), extremes and counts
// (truncation).
#pragma once

#include <cstddef>

namespace sdfcontour::detail {

/// out[k] = 1 where row[k] (k in [from, to)) has a neighbour of the other sign (value < 0 or not)
/// at k - 1, k + 1 or `offset[0..3]` values away (the rows beside it), else 0.
void crossing_row(const float* row, const std::ptrdiff_t offset[4], int from, int to,
                  unsigned char* out);
void crossing_row(const double* row, const std::ptrdiff_t offset[4], int from, int to,
                  unsigned char* out);

/// out[k] = 1 where |row[k]| < near (k in [from, to)), else 0.
void near_row(const float* row, double near, int from, int to, unsigned char* out);
void near_row(const double* row, double near, int from, int to, unsigned char* out);

/// lo = min(lo, values), hi = max(hi, values) over n finite values.
void extremes(const float* values, std::size_t n, double& lo, double& hi);
void extremes(const double* values, std::size_t n, double& lo, double& hi);

/// Adds to `negatives` the values < 0, to `at_inside` those < 0 with -value >= inside, to
/// `at_outside` those > 0 with value >= outside (each value widened to double).
void count_beyond(const float* values, std::size_t n, double inside, double outside,
                  long& negatives, long& at_inside, long& at_outside);
void count_beyond(const double* values, std::size_t n, double inside, double outside,
                  long& negatives, long& at_inside, long& at_outside);

}  // namespace sdfcontour::detail
