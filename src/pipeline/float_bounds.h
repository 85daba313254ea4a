// Internal: a double rounded to the float on either side of it, for compact bounds that must
// still hold the value (boxes, radii) where an exact test in doubles follows.
#pragma once

#include <cmath>

namespace sdfcontour::detail {

/// The largest float <= x.
inline float float_below(double x) {
  const float f = float(x);
  return double(f) > x ? std::nextafter(f, -INFINITY) : f;
}

/// The smallest float >= x.
inline float float_above(double x) {
  const float f = float(x);
  return double(f) < x ? std::nextafter(f, INFINITY) : f;
}

}  // namespace sdfcontour::detail
