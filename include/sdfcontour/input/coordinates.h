// The range of coordinates the library accepts for meshes and points.
#pragma once

#include <string>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Larger coordinates overflow CGAL's exact predicates (products of up to ten of them must stay
/// below double's 1e308) and end in a floating-point trap; real meshes are far smaller.
constexpr double kLargestCoordinate = 1e30;

/// Throws Error ("`what` has a NaN, infinite or too large ... (row r)") unless every entry of
/// `points` (n x 3) is finite and at most kLargestCoordinate in absolute value.
void require_coordinates(const PointMatrix& points, const std::string& what);

}  // namespace sdfcontour
