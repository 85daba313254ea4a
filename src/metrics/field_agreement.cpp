#include "sdfcontour/metrics/field_agreement.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace sdfcontour {

namespace {

// The trilinear interpolant at p of the samples value_at(i, j, k) of a grid of `geometry`.
template <class ValueAt>
double trilinear(const GridGeometry& geometry, const ValueAt& value_at, const Eigen::Vector3d& p) {
  const Eigen::Vector3d h = geometry.spacing();
  int base[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    const double u =
        std::clamp((p[a] - geometry.bounds.min[a]) / h[a], 0.0, double(geometry.dims[a] - 1));
    base[a] = std::min(int(u), geometry.dims[a] - 2);
    t[a] = u - base[a];
  }
  double value = 0;
  for (int c = 0; c < 8; ++c) {
    const int di = c >> 2, dj = (c >> 1) & 1, dk = c & 1;
    const double w = (di ? t[0] : 1 - t[0]) * (dj ? t[1] : 1 - t[1]) * (dk ? t[2] : 1 - t[2]);
    value += w * value_at(base[0] + di, base[1] + dj, base[2] + dk);
  }
  return value;
}

template <class Grid>
double fraction_off(const Grid& grid, const Mesh& mesh, double tolerance, double scale) {
  const Eigen::Index n = mesh.vertices.rows();
  if (n == 0) return 0;
  const long off = tbb::parallel_reduce(
      tbb::blocked_range<Eigen::Index>(0, n), 0L,
      [&](const tbb::blocked_range<Eigen::Index>& r, long count) {
        for (Eigen::Index v = r.begin(); v < r.end(); ++v)
          count += !(std::abs(scale * trilinear_value(grid, mesh.vertices.row(v).transpose())) <=
                     tolerance);
        return count;
      },
      std::plus<long>());
  return double(off) / double(n);
}

}  // namespace

double trilinear_value(const GridView& grid, const Eigen::Vector3d& p) {
  return trilinear(
      grid, [&](int i, int j, int k) { return grid.value(grid.index(i, j, k)); }, p);
}

double trilinear_value(const SparseGrid& grid, const Eigen::Vector3d& p) {
  return trilinear(
      grid, [&](int i, int j, int k) { return grid.value(i, j, k); }, p);
}

double fraction_off_zero_set(const GridView& grid, const Mesh& mesh, double tolerance,
                             double scale) {
  return fraction_off(grid, mesh, tolerance, scale);
}

double fraction_off_zero_set(const SparseGrid& grid, const Mesh& mesh, double tolerance,
                             double scale) {
  return fraction_off(grid, mesh, tolerance, scale);
}

}  // namespace sdfcontour
