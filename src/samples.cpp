#include "sdfcontour/samples.h"

#include <cmath>
#include <string>

namespace sdfcontour {

Eigen::Vector3d Grid::spacing() const {
  Eigen::Vector3d h;
  for (int a = 0; a < 3; ++a) h[a] = (bounds.max[a] - bounds.min[a]) / (dims[a] - 1);
  return h;
}

Eigen::Vector3d Grid::point(int i, int j, int k) const {
  const Eigen::Vector3d h = spacing();
  return bounds.min + Eigen::Vector3d(i * h[0], j * h[1], k * h[2]);
}

Samples Grid::to_samples() const {
  Samples s;
  s.points.resize(Eigen::Index(size()), 3);
  s.values = values;
  for (int i = 0; i < dims[0]; ++i)
    for (int j = 0; j < dims[1]; ++j)
      for (int k = 0; k < dims[2]; ++k) s.points.row(Eigen::Index(index(i, j, k))) = point(i, j, k);
  return s;
}

static void require_finite(const Eigen::VectorXd& values, const char* what) {
  for (Eigen::Index i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw Error(std::string(what) + " contain a NaN or infinite value (at index " +
                  std::to_string(i) + ")");
}

void validate_grid(const Grid& grid) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2)
      throw Error("grid has " + std::to_string(grid.dims[a]) +
                  " samples along an axis; at least 2 are needed on each axis");
  for (int a = 0; a < 3; ++a)
    if (!(grid.bounds.min[a] < grid.bounds.max[a]))
      throw Error("bounds must have min < max on every axis");
  if (std::size_t(grid.values.size()) != grid.size())
    throw Error("grid values do not match its dimensions");
  require_finite(grid.values, "grid values");
}

void validate_samples(const Samples& samples) {
  if (samples.points.rows() != samples.values.size())
    throw Error("samples have " + std::to_string(samples.points.rows()) + " points but " +
                std::to_string(samples.values.size()) + " values");
  if (samples.points.rows() < 4)
    throw Error("need at least 4 samples, got " + std::to_string(samples.points.rows()));
  for (Eigen::Index i = 0; i < samples.points.rows(); ++i)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(samples.points(i, a)))
        throw Error("sample positions contain a NaN or infinite value (at row " +
                    std::to_string(i) + ")");
  require_finite(samples.values, "sample values");
}

void require_sign_change(const Eigen::VectorXd& values) {
  bool inside = false, outside = false;
  for (Eigen::Index i = 0; i < values.size(); ++i) (values[i] < 0 ? inside : outside) = true;
  if (!(inside && outside))
    throw Error(std::string("no surface: every value is ") +
                (inside ? "negative" : "non-negative") + ", so the field has no sign change");
}

}  // namespace sdfcontour
