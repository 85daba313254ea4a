// SDF samples: scattered (points + values) and on a regular grid.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

/// Scattered samples of a signed distance function (negative inside).
struct Samples {
  PointMatrix points;      ///< n x 3 sample positions
  Eigen::VectorXd values;  ///< n signed distances, values(i) at points.row(i)
};

/// The samples at `rows` (indices into `samples`), in that order.
template <class Index>
Samples samples_at(const Samples& samples, const std::vector<Index>& rows) {
  Samples out;
  out.points.resize(Eigen::Index(rows.size()), 3);
  out.values.resize(Eigen::Index(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    out.points.row(Eigen::Index(r)) = samples.points.row(Eigen::Index(rows[r]));
    out.values[Eigen::Index(r)] = samples.values[Eigen::Index(rows[r])];
  }
  return out;
}

/// Axis-aligned box [min, max].
struct Bounds {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(-1.0);
  Eigen::Vector3d max = Eigen::Vector3d::Constant(1.0);
};

/// Where a regular grid's samples lie: sample (i,j,k) at min + (i*hx, j*hy, k*hz), with samples
/// at both ends of each axis (h = (max - min) / (n - 1)); C order, index (i*ny + j)*nz + k.
///
/// A block of a larger grid (a brick with its halo) keeps the larger grid's `bounds` and names it
/// by `whole` (its dims) and `first` (the global index of the block's sample (0, 0, 0)): its
/// samples then lie at bounds.min + (first + (i, j, k)) * h, computed by the same formula as the
/// whole grid's, bit for bit.
struct GridGeometry {
  std::array<int, 3> dims{0, 0, 0};   ///< (nx, ny, nz), each >= 2
  Bounds bounds;                      ///< positions of the first and last samples (of `whole`)
  std::array<int, 3> first{0, 0, 0};  ///< a block's offset in the whole grid (0: no block)
  std::array<int, 3> whole{0, 0, 0};  ///< the whole grid's dims (0: this grid is whole)

  std::size_t size() const { return std::size_t(dims[0]) * dims[1] * dims[2]; }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(i) * dims[1] + j) * dims[2] + k;
  }
  /// The whole grid's dims (`dims` unless this is a block).
  std::array<int, 3> whole_dims() const { return whole[0] > 0 ? whole : dims; }
  Eigen::Vector3d spacing() const;
  Eigen::Vector3d point(int i, int j, int k) const;
};

/// Samples on a regular grid, owning its values as doubles.
struct Grid : GridGeometry {
  Eigen::VectorXd values;  ///< size() values in C order

  /// The grid's samples as scattered samples, in the grid's C order.
  Samples to_samples() const;
};

enum class ScalarType { Float32, Float64 };

/// A read-only view of grid values stored elsewhere (a Grid, a memory-mapped .npy), float32 or
/// float64, so a large grid is never copied or widened.
struct GridView : GridGeometry {
  const void* data = nullptr;  ///< size() values of `type` in C order
  ScalarType type = ScalarType::Float64;
  /// Set where the values lie in a file mapping (a mapped .npy): whole-grid passes hand it the
  /// values they are done with, (*drop_pages)(address, bytes), and it drops those pages from
  /// memory (read from the file again if used), so a pass over a grid larger than memory holds a
  /// window of it. It ignores whatever lies outside its mapping. Null: the values stay.
  const std::function<void(const void*, std::size_t)>* drop_pages = nullptr;
  /// Set by whoever made the view once it has checked its values finite (a .npy's reader):
  /// validate_grid then checks the dims and bounds alone instead of passing over the values
  /// again. Views made from it with other values start unset.
  bool values_checked = false;

  double value(std::size_t p) const {
    return type == ScalarType::Float32 ? double(static_cast<const float*>(data)[p])
                                       : static_cast<const double*>(data)[p];
  }
  /// Calls f(const T* values) with T the stored type: one dispatch for a whole loop.
  template <class F>
  decltype(auto) visit(F&& f) const {
    if (type == ScalarType::Float32) return f(static_cast<const float*>(data));
    return f(static_cast<const double*>(data));
  }
};

/// A view of `grid`'s values (valid while `grid` lives).
GridView view_of(const Grid& grid);

/// Throws Error unless: dims >= 2 on every axis, values match dims, values finite (unless
/// `grid.values_checked`), bounds min < max on every axis.
void validate_grid(const GridView& grid);
void validate_grid(const Grid& grid);
/// The dims and bounds part of validate_grid.
void validate_grid_geometry(const GridGeometry& grid);

/// The (i, j, k) in its whole grid (GridGeometry::first added) of the first value in C order
/// that is NaN, infinite or over 1e100 in size; nullopt if there is none. Parallel.
std::optional<std::array<int, 3>> first_non_finite(const GridView& grid);

/// Throws Error unless: points is n x 3 and values has n finite entries, n >= 4,
/// and every coordinate is finite.
void validate_samples(const Samples& samples);

/// Throws Error if the values have no sign change (no surface: all >= 0 or all < 0).
void require_sign_change(const Eigen::VectorXd& values);
void require_sign_change(const GridView& grid);

}  // namespace sdfcontour
