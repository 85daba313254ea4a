// SDF samples: scattered (points + values) and on a regular grid.
#pragma once

#include <array>
#include <cstddef>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Scattered samples of a signed distance function (negative inside).
struct Samples {
  PointMatrix points;      ///< n x 3 sample positions
  Eigen::VectorXd values;  ///< n signed distances, values(i) at points.row(i)
};

/// Axis-aligned box [min, max].
struct Bounds {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(-1.0);
  Eigen::Vector3d max = Eigen::Vector3d::Constant(1.0);
};

/// Samples on a regular grid: value(i,j,k) is the SDF at min + (i*hx, j*hy, k*hz),
/// with samples at both ends of each axis (h = (max - min) / (n - 1)).
struct Grid {
  std::array<int, 3> dims{0, 0, 0};  ///< (nx, ny, nz), each >= 2
  Bounds bounds;                     ///< positions of the first and last samples
  Eigen::VectorXd values;            ///< nx*ny*nz values in C order: index (i*ny + j)*nz + k

  std::size_t size() const { return std::size_t(dims[0]) * dims[1] * dims[2]; }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(i) * dims[1] + j) * dims[2] + k;
  }
  Eigen::Vector3d spacing() const;
  Eigen::Vector3d point(int i, int j, int k) const;
  /// The grid's samples as scattered samples, in the grid's C order.
  Samples to_samples() const;
};

/// Throws Error unless: dims >= 2 on every axis, values match dims, values finite,
/// bounds min < max on every axis.
void validate_grid(const Grid& grid);

/// Throws Error unless: points is n x 3 and values has n finite entries, n >= 4,
/// and every coordinate is finite.
void validate_samples(const Samples& samples);

/// Throws Error if the values have no sign change (no surface: all >= 0 or all < 0).
void require_sign_change(const Eigen::VectorXd& values);

}  // namespace sdfcontour
