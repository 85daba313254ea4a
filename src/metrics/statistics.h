// Small summary statistics over samples of a quantity.
#pragma once

#include <vector>

namespace sdfcontour {

/// The q-quantile (0 <= q <= 1) of `values` with linear interpolation between order statistics
/// (NumPy's default). NaN for an empty input.
double quantile(std::vector<double> values, double q);

/// Arithmetic mean; NaN for an empty input.
double mean(const std::vector<double>& values);

}  // namespace sdfcontour
