// Each scan has an AVX2 clone (cpu_clones.h). The extremes are vectorised as fast math allows:
// over finite values a minimum is the same number in any order (a zero's sign aside, which no
// caller reads).
#include "input/value_scans.h"

#include <algorithm>
#include <cmath>

#include "input/cpu_clones.h"

namespace sdfcontour::detail {

template <class T>
SDFCONTOUR_AVX2_CLONE void crossing_row(const T* __restrict row, const std::ptrdiff_t offset[4],
                                        int from, int to, unsigned char* __restrict out) {
  const T* __restrict a = row + offset[0];
  const T* __restrict b = row + offset[1];
  const T* __restrict c = row + offset[2];
  const T* __restrict d = row + offset[3];
  for (int k = from; k < to; ++k) {
    const bool in = row[k] < 0;
    out[k] = (in != (a[k] < 0)) | (in != (b[k] < 0)) | (in != (c[k] < 0)) | (in != (d[k] < 0)) |
             (in != (row[k - 1] < 0)) | (in != (row[k + 1] < 0));
  }
}

template <class T>
SDFCONTOUR_AVX2_CLONE void near_row(const T* __restrict row, double near, int from, int to,
                                    unsigned char* __restrict out) {
  for (int k = from; k < to; ++k) out[k] = std::abs(double(row[k])) < near;
}

template <class T>
SDFCONTOUR_AVX2_CLONE_FAST_MATH void extremes(const T* __restrict values, std::size_t n, double& lo,
                                              double& hi) {
  T a = T(lo), b = T(hi);
  for (std::size_t i = 0; i < n; ++i) {
    a = values[i] < a ? values[i] : a;
    b = values[i] > b ? values[i] : b;
  }
  lo = std::min(lo, double(a));
  hi = std::max(hi, double(b));
}

template <class T>
SDFCONTOUR_AVX2_CLONE void count_beyond(const T* __restrict values, std::size_t n, double inside,
                                        double outside, long& negatives, long& at_inside,
                                        long& at_outside) {
  long a = 0, b = 0, c = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = values[i];
    a += v < 0;
    b += (v < 0) & (-v >= inside);
    c += (v > 0) & (v >= outside);
  }
  negatives += a, at_inside += b, at_outside += c;
}

#define SDFCONTOUR_VALUE_SCANS(T)                                                             \
  template void crossing_row<T>(const T*, const std::ptrdiff_t[4], int, int, unsigned char*); \
  template void near_row<T>(const T*, double, int, int, unsigned char*);                      \
  template void extremes<T>(const T*, std::size_t, double&, double&);                         \
  template void count_beyond<T>(const T*, std::size_t, double, double, long&, long&, long&);
SDFCONTOUR_VALUE_SCANS(float)
SDFCONTOUR_VALUE_SCANS(double)
#undef SDFCONTOUR_VALUE_SCANS

}  // namespace sdfcontour::detail
