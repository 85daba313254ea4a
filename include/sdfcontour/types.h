// Plain array types shared by every pipeline stage, and the library's error type.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <atomic>
#include <stdexcept>
#include <string>

namespace sdfcontour {

/// n x 3 row-major array of 3D points (or vectors): row i is (x, y, z).
using PointMatrix = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// m x 4 row-major array of tetrahedra: row t holds four sample indices, positively oriented.
using TetMatrix = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// f x 3 row-major array of triangles: row f holds three vertex indices, counter-clockwise
/// seen from outside.
using TriangleMatrix = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// A triangle mesh: vertices (n x 3) and triangles (f x 3) indexing into them.
struct Mesh {
  PointMatrix vertices;
  TriangleMatrix triangles;
};

/// Points with unit normals, row i of `normals` belonging to row i of `points`.
struct OrientedPoints {
  PointMatrix points;   ///< k x 3 positions
  PointMatrix normals;  ///< k x 3 outward normals (any length but zero)
  /// Empty (every point counts as 1) or k confidences in (0, 1]: a point's normal and screening
  /// terms are scaled by it, so a less reliable point pulls the surface less.
  Eigen::VectorXd weights;
};

/// Every error the library reports: a one-line, user-facing message. Thrown as is, it blames the
/// input (a bad value, shape, option or file content).
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A file that cannot be opened, read, written or renamed (the operating system said no).
class IoError : public Error {
 public:
  explicit IoError(const std::string& message) : Error(message) {}
};

/// The caller asked to stop (ContourOptions::cancel or PoissonOptions::cancel became true).
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

/// Throws Cancelled if `flag` is set.
inline void check_cancel(const std::atomic<bool>* flag) {
  if (flag && flag->load(std::memory_order_relaxed)) throw Cancelled();
}

/// A broken invariant inside sdfcontour: a bug to report, not the user's fault.
class InternalError : public Error {
 public:
  explicit InternalError(const std::string& message) : Error(message) {}
};

}  // namespace sdfcontour
