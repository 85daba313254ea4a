#include "reconstruction/poisson/density.h"

#include <cmath>

#include "reconstruction/poisson/bspline.h"

namespace sdfcontour::poisson {

SamplingDensity::SamplingDensity(const std::vector<UnitPoint>& points, const MortonRuns& runs,
                                 int depth)
    : res_(1L << depth), h_(1.0 / double(res_)) {
  // Unit weights splatted per cell (a run of Morton-ordered points), then gathered per node.
  std::vector<Key> run_keys;
  std::vector<std::array<std::uint32_t, 2>> run_ranges;
  runs.for_each_run(depth, [&](const std::array<long, 3>& c, std::size_t first, std::size_t last) {
    run_keys.push_back(pack(c[0], c[1], c[2]));
    run_ranges.push_back({std::uint32_t(first), std::uint32_t(last)});
  });
  std::vector<std::array<double, 8>> corner_sums(run_keys.size());
  std::vector<Key> corners(8 * run_keys.size());
  tbb::parallel_for(std::size_t(0), run_keys.size(), [&](std::size_t r) {
    const auto c = unpack(run_keys[r]);
    corner_sums[r].fill(0.0);
    for (std::uint32_t q = run_ranges[r][0]; q < run_ranges[r][1]; ++q) {
      const auto w = corner_weights(points[runs.point(q)].p, c, res_);
      for (int a = 0; a < 8; ++a) corner_sums[r][std::size_t(a)] += w[std::size_t(a)];
    }
    for (int a = 0; a < 8; ++a)
      corners[8 * r + std::size_t(a)] =
          pack(c[0] + (a & 1), c[1] + (a >> 1 & 1), c[2] + (a >> 2 & 1));
  });
  sort_unique(corners);
  nodes_ = std::move(corners);
  values_.assign(nodes_.size(), 0.0);
  const KeyIndex run_index(run_keys);
  tbb::parallel_for(std::size_t(0), nodes_.size(), [&](std::size_t v) {
    const auto [i, j, k] = unpack(nodes_[v]);
    for (int c = 0; c < 8; ++c) {
      const long ci = i + (c & 1) - 1, cj = j + (c >> 1 & 1) - 1, ck = k + (c >> 2 & 1) - 1;
      if (ci < 0 || cj < 0 || ck < 0) continue;
      const int r = run_index.find(pack(ci, cj, ck));
      if (r >= 0) values_[v] += corner_sums[std::size_t(r)][std::size_t(7 - c)];
    }
  });
  // Smoothing makes the estimate at a point hardly depend on where it sits inside its cell.
  for (int axis = 0; axis < 3; ++axis) smooth(axis);
  index_ = KeyIndex(nodes_);
}

void SamplingDensity::smooth(int axis) {
  const KeyIndex index(nodes_);
  std::vector<Key> grown;
  grown.reserve(nodes_.size() * 3);
  for (Key key : nodes_) {
    auto c = unpack(key);
    for (long o = -1; o <= 1; ++o) {
      auto d = c;
      d[std::size_t(axis)] += o;
      if (d[std::size_t(axis)] >= 0 && d[std::size_t(axis)] <= res_)
        grown.push_back(pack(d[0], d[1], d[2]));
    }
  }
  sort_unique(grown);
  std::vector<double> blurred(grown.size(), 0.0);
  tbb::parallel_for(std::size_t(0), grown.size(), [&](std::size_t g) {
    auto c = unpack(grown[g]);
    double sum = 0;
    for (long o = -1; o <= 1; ++o) {
      auto d = c;
      d[std::size_t(axis)] += o;
      if (d[std::size_t(axis)] < 0 || d[std::size_t(axis)] > res_) continue;
      const int idx = index.find(pack(d[0], d[1], d[2]));
      if (idx >= 0) sum += (o == 0 ? 0.5 : 0.25) * values_[std::size_t(idx)];
    }
    blurred[g] = sum;
  });
  nodes_ = std::move(grown);
  values_ = std::move(blurred);
}

double SamplingDensity::points_per_area(const Eigen::Vector3d& p) const {
  const auto c = cell_of(p, res_);
  const auto w = corner_weights(p, c, res_);
  double sum = 0;
  for (int q = 0; q < 8; ++q) {
    const int idx = index_.find(pack(c[0] + (q & 1), c[1] + (q >> 1 & 1), c[2] + (q >> 2 & 1)));
    if (idx >= 0) sum += w[std::size_t(q)] * values_[std::size_t(idx)];
  }
  return 12.0 / 5.0 * sum / (h_ * h_);
}

double assign_areas_and_depths(std::vector<UnitPoint>& points, const SamplingDensity& density,
                               double samples_per_node, int min_depth, int max_depth,
                               bool fractional) {
  double total_area = 0;
  for (auto& s : points) {
    const double sigma = std::max(density.points_per_area(s.p), 1e-300);
    s.area = 1.0 / sigma;
    total_area += s.area;
    // Depth where a node of side h holds sigma * h^2 = samples_per_node points.
    const double ideal = 0.5 * std::log2(sigma / samples_per_node);
    if (!fractional) {
      s.depth = std::clamp(int(std::lround(ideal)), min_depth, max_depth);
      continue;
    }
    const double depth = std::clamp(ideal, double(min_depth), double(max_depth));
    s.depth = std::min(int(std::floor(depth)), max_depth);
    s.finer_share = s.depth < max_depth ? depth - s.depth : 0.0;
  }
  return total_area / double(points.size());
}

}  // namespace sdfcontour::poisson
