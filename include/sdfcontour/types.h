// Plain array types shared by every pipeline stage, and the library's error type.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
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
  PointMatrix points;
  PointMatrix normals;
};

/// Every error the library reports about its input: a one-line, user-facing message.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace sdfcontour
