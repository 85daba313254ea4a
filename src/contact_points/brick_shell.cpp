#include "contact_points/brick_shell.h"

#include <algorithm>
#include <cmath>

namespace sdfcontour {

namespace {
// At most this many buckets per axis: a retry's box can grow to the whole band.
constexpr int kMaxBucketsPerAxis = 128;
}  // namespace

BrickShell::BrickShell(const PointMatrix& points, const Eigen::VectorXd& values,
                       const std::vector<int>& rows, const BrickBox& outer, double cell)
    : outer_(outer) {
  const Eigen::Vector3d extent = outer.max - outer.min;
  cell_ = std::max(cell, extent.maxCoeff() / kMaxBucketsPerAxis);
  if (!(cell_ > 0) || !std::isfinite(cell_)) cell_ = 1;
  for (int a = 0; a < 3; ++a)
    dims_[std::size_t(a)] = std::max(1, int(std::ceil(extent[a] / cell_)));
  auto bucket = [&](const Eigen::Vector3d& p) {
    int b = 0;
    for (int a = 0; a < 3; ++a)
      b = b * dims_[std::size_t(a)] +
          std::clamp(int(std::floor((p[a] - outer_.min[a]) / cell_)), 0, dims_[std::size_t(a)] - 1);
    return b;
  };
  offsets_.assign(std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]) + 1, 0);
  std::vector<int> bucket_of(rows.size());
  for (std::size_t q = 0; q < rows.size(); ++q) {
    bucket_of[q] = bucket(points.row(rows[q]).transpose());
    ++offsets_[std::size_t(bucket_of[q]) + 1];
  }
  for (std::size_t b = 1; b < offsets_.size(); ++b) offsets_[b] += offsets_[b - 1];
  samples_.resize(rows.size());
  std::vector<int> fill(offsets_.begin(), offsets_.end() - 1);
  for (std::size_t q = 0; q < rows.size(); ++q) {
    const int r = rows[q];
    samples_[std::size_t(fill[std::size_t(bucket_of[q])]++)] = {
        points(r, 0), points(r, 1), points(r, 2), values[r] * values[r]};
  }
}

bool BrickShell::conflict_free(const Eigen::Vector3d& c, double r2, double reach,
                               double margin) const {
  if (samples_.empty()) return true;
  std::array<int, 3> lo, hi;
  for (int a = 0; a < 3; ++a) {
    const int last = dims_[std::size_t(a)] - 1;
    lo[std::size_t(a)] =
        std::clamp(int(std::floor((c[a] - reach - outer_.min[a]) / cell_)), 0, last);
    hi[std::size_t(a)] =
        std::clamp(int(std::floor((c[a] + reach - outer_.min[a]) / cell_)), 0, last);
  }
  for (int i = lo[0]; i <= hi[0]; ++i)
    for (int j = lo[1]; j <= hi[1]; ++j) {
      const int row = (i * dims_[1] + j) * dims_[2];
      for (int q = offsets_[std::size_t(row + lo[2])]; q < offsets_[std::size_t(row + hi[2]) + 1];
           ++q) {
        const Eigen::Vector4d& s = samples_[std::size_t(q)];
        const double power2 = r2 + s[3];
        if (power2 <= -margin * margin) continue;  // its sphere and this one are apart
        const double d = (s.head<3>() - c).norm();
        if (d <= std::sqrt(std::max(power2, 0.0)) + margin) return false;
      }
    }
  return true;
}

}  // namespace sdfcontour
