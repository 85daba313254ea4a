// NumPy .npy files: float32/float64 arrays in C order, and the two sample layouts built on them.
#pragma once

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "sdfcontour/input/samples.h"
#include "sdfcontour/input/sdf_input.h"

namespace sdfcontour {

/// A dense array read from a .npy file, converted to double.
struct NpyArray {
  std::vector<std::size_t> shape;  ///< the array's shape, C order
  std::vector<double> data;        ///< product(shape) values in C order
};

/// A .npy file mapped read-only into memory: nothing is read until used, and a grid larger than
/// memory can be contoured by the methods that visit it once (mc, the band's selection).
struct MappedNpy {
  std::vector<std::size_t> shape;  ///< the array's shape, C order
  std::size_t count = 0;           ///< product(shape)
  ScalarType type = ScalarType::Float64;
  const char* data = nullptr;  ///< count values of `type`, little-endian, C order (maybe unaligned)
  std::shared_ptr<const void> file;  ///< keeps the mapping alive

  /// Value i, widened to double (safe for unaligned data).
  double value(std::size_t i) const {
    if (type == ScalarType::Float32) {
      float v;
      std::memcpy(&v, data + 4 * i, 4);
      return v;
    }
    double v;
    std::memcpy(&v, data + 8 * i, 8);
    return v;
  }
};

/// Maps a little-endian float32 or float64 C-order .npy file (format versions 1-3). The header
/// is parsed by hand with a size cap, every dimension and their product are checked against the
/// file's size. Throws Error naming the problem for an unreadable, truncated or corrupt file, a
/// Fortran-order array or any other dtype.
std::shared_ptr<const MappedNpy> map_npy(const std::string& path);

/// Reads a little-endian float32 or float64 C-order .npy file (format versions 1-3).
/// Throws Error naming the problem for an unreadable, truncated or corrupt file, a Fortran-order
/// array or any other dtype.
NpyArray read_npy(const std::string& path);

/// Writes `count` values (C order; count must be product(shape), else InternalError) as a
/// float64 or float32 (`type`) .npy file, atomically. Float32 is converted a chunk at a time, so
/// the writer holds no copy of the values.
void write_npy(const std::string& path, const std::vector<std::size_t>& shape, const double* values,
               std::size_t count, ScalarType type);
/// Writes `data` (C order, product(shape) values) as a float64 .npy file, atomically.
void write_npy(const std::string& path, const std::vector<std::size_t>& shape,
               const std::vector<double>& data);

/// What an input holds: a grid of shape (nx, ny, nz) or scattered samples of shape (n, 4).
/// Interprets an array as a grid (3 dimensions; positions from `bounds`) or as scattered samples
/// (shape (n, 4): x, y, z, value). Validates it (finite, enough samples) and throws Error
/// otherwise.
SdfInput sdf_input_from_array(const NpyArray& array, const Bounds& bounds);

/// The same for a mapped .npy: a grid is viewed in place (no copy, float32 stays float32),
/// scattered samples are copied.
SdfInput sdf_input_from_npy(std::shared_ptr<const MappedNpy> array, const Bounds& bounds);

}  // namespace sdfcontour
