// Internal: the k-th smallest of many values, selected in parallel.
#pragma once

#include <cstddef>
#include <vector>

namespace sdfcontour::detail {

/// A run of values (not owned).
struct ValueRun {
  const double* data;
  std::size_t size;
};

/// The value that std::nth_element would put at rank k (0-based) of all the runs' values taken
/// together (none of them NaN; k below their count): a radix selection on the values' bits, 16
/// at a time, each pass a histogram counted in parallel. The same value for any thread count, with
/// no copy of the values and no serial pass over them.
double kth_smallest(const std::vector<ValueRun>& runs, std::size_t k);

/// The same over one vector.
inline double kth_smallest(const std::vector<double>& values, std::size_t k) {
  return kth_smallest(std::vector<ValueRun>{{values.data(), values.size()}}, k);
}

}  // namespace sdfcontour::detail
