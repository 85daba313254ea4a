#include "sdfcontour/band/point_clusters.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace sdfcontour {

std::vector<int> point_clusters(const PointMatrix& points, double cell) {
  if (!(cell > 0) || !std::isfinite(cell)) throw Error("the cluster cell must be positive");
  const Eigen::Index n = points.rows();
  if (n == 0) return {};
  using Key = std::array<long, 3>;
  const Eigen::Vector3d origin = points.colwise().minCoeff().transpose();
  std::vector<Key> key(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      key[std::size_t(i)][std::size_t(a)] =
          long(std::min(std::floor((points(i, a) - origin[a]) / cell), 1e15));
  std::vector<Key> cells = key;
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  auto find_cell = [&](const Key& k) {
    const auto it = std::lower_bound(cells.begin(), cells.end(), k);
    return it != cells.end() && *it == k ? long(it - cells.begin()) : -1L;
  };
  // Union-find over the occupied cells, joined to their occupied neighbours.
  std::vector<long> parent(cells.size());
  std::iota(parent.begin(), parent.end(), 0L);
  auto root = [&](long x) {
    while (parent[std::size_t(x)] != x)
      x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
  };
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const long other = find_cell({cells[c][0] + dx, cells[c][1] + dy, cells[c][2] + dz});
          if (other < 0) continue;
          const long a = root(long(c)), b = root(other);
          if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
        }
  // Number the clusters by their first row.
  std::vector<int> number(cells.size(), -1), out(static_cast<std::size_t>(n));
  int clusters = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const long r = root(find_cell(key[std::size_t(i)]));
    if (number[std::size_t(r)] < 0) number[std::size_t(r)] = clusters++;
    out[std::size_t(i)] = number[std::size_t(r)];
  }
  return out;
}

}  // namespace sdfcontour
