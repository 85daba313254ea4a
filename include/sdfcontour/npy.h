// NumPy .npy files: float32/float64 arrays in C order, and the two sample layouts built on them.
#pragma once

#include <string>
#include <vector>

#include "sdfcontour/samples.h"

namespace sdfcontour {

/// A dense array read from a .npy file, converted to double.
struct NpyArray {
  std::vector<std::size_t> shape;  ///< the array's shape, C order
  std::vector<double> data;        ///< product(shape) values in C order
};

/// Reads a little-endian float32 or float64 C-order .npy file (format versions 1-3).
/// Throws Error naming the problem for an unreadable, truncated or corrupt file, a Fortran-order
/// array or any other dtype.
NpyArray read_npy(const std::string& path);

/// Writes `data` (C order, product(shape) values) as a float64 .npy file, atomically.
void write_npy(const std::string& path, const std::vector<std::size_t>& shape,
               const std::vector<double>& data);

/// What an input .npy holds: a grid of shape (nx, ny, nz) or scattered samples of shape (n, 4).
struct SdfInput {
  bool is_grid = false;
  Grid grid;        ///< valid when is_grid
  Samples samples;  ///< the scattered samples, when !is_grid (grid.to_samples() gives a grid's)
};

/// Interprets an array as a grid (3 dimensions; positions from `bounds`) or as scattered samples
/// (shape (n, 4): x, y, z, value). Validates it (finite, enough samples) and throws Error
/// otherwise.
SdfInput sdf_input_from_array(const NpyArray& array, const Bounds& bounds);

}  // namespace sdfcontour
