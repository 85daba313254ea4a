#include "reconstruction/poisson/indicator.h"

#include "reconstruction/poisson/bspline.h"

namespace sdfcontour::poisson {

double interpolate(const OctreeLevel& L, const std::vector<double>& x,
                   const std::array<long, 3>& cell, const Eigen::Vector3d& p) {
  const auto w = corner_weights(p, cell, L.res);
  double v = 0;
  for (int c = 0; c < 8; ++c)
    if (w[std::size_t(c)] != 0)
      v +=
          w[std::size_t(c)] *
          x[std::size_t(L.node(cell[0] + (c & 1), cell[1] + (c >> 1 & 1), cell[2] + (c >> 2 & 1)))];
  return v;
}

Indicator::Location Indicator::locate(const Eigen::Vector3d& p) const {
  for (int d = tree_.finest; d >= tree_.min_depth; --d) {
    const OctreeLevel& L = tree_.level(d);
    const auto c = cell_of(p, L.res);
    if (L.cell(pack(c[0], c[1], c[2])) >= 0) return {d, c};
  }
  return {};
}

double Indicator::at(const Eigen::Vector3d& p) const {
  const Location at = locate(p);
  if (at.depth < 0) return 0.0;
  return interpolate(tree_.level(at.depth), values_[std::size_t(at.depth)], at.cell, p);
}

double Indicator::at_finest_node(long i, long j, long k, double outside) const {
  const long R = tree_.level(tree_.finest).res;
  if (i < 0 || j < 0 || k < 0 || i > R || j > R || k > R) return outside;
  for (int d = tree_.finest; d >= tree_.min_depth; --d) {
    const OctreeLevel& L = tree_.level(d);
    const int shift = tree_.finest - d;
    const long m = (1L << shift) - 1;
    if (!(i & m) && !(j & m) && !(k & m)) {
      const int idx = L.node(i >> shift, j >> shift, k >> shift);
      if (idx >= 0) return values_[std::size_t(d)][std::size_t(idx)];
    }
    const std::array<long, 3> c{std::min(i >> shift, L.res - 1), std::min(j >> shift, L.res - 1),
                                std::min(k >> shift, L.res - 1)};
    if (L.cell(pack(c[0], c[1], c[2])) >= 0) {
      const Eigen::Vector3d p(double(i) / double(R), double(j) / double(R), double(k) / double(R));
      return interpolate(L, values_[std::size_t(d)], c, p);
    }
  }
  return outside;
}

}  // namespace sdfcontour::poisson
