// Internal: the floating-point certificates of the crossing search (self_intersections.cpp's
// stars, triangle_pairs.cpp's pairs), which hold only with a margin far beyond rounding.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sdfcontour::detail {

// The margin a certificate needs to spare, relative to the lengths it compares.
constexpr double kClear = 1e-9;

// Whether y lies clearly counter-clockwise of x seen along the unit vector n (their 2D cross
// product in the plane normal to n, n . (x cross y), beyond kClear times their lengths).
inline bool clearly_turns(const Eigen::Vector3d& n, const Eigen::Vector3d& x,
                          const Eigen::Vector3d& y) {
  return n.dot(x.cross(y)) > kClear * x.norm() * y.norm();
}

}  // namespace sdfcontour::detail
