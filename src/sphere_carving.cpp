#include "sdfcontour/sphere_carving.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace sdfcontour {

namespace {

// The mesh's vertices bucketed in cubes of side `cell`, by column (i, j) and, within a column,
// by height k: the vertices a ball can hold are found column by column.
class VertexColumns {
 public:
  // Over the vertices `which` of V.
  VertexColumns(const PointMatrix& V, const std::vector<int>& which, double cell) : cell_(cell) {
    origin_ = V.row(which[0]).transpose();
    Eigen::Vector3d top = origin_;
    for (int v : which) {
      origin_ = origin_.cwiseMin(V.row(v).transpose());
      top = top.cwiseMax(V.row(v).transpose());
    }
    const Eigen::Vector3d extent = top - origin_;
    // Keep the column table modest and the heights within an int whatever the spacing: coarser
    // cubes only cost more tests.
    while ((extent[0] / cell_ + 1) * (extent[1] / cell_ + 1) > 6.4e7 || extent[2] / cell_ > 1e9)
      cell_ *= 2;
    for (int a = 0; a < 3; ++a) size_[a] = long(extent[a] / cell_) + 1;
    std::vector<std::pair<long, int>> keyed(which.size(), {0, 0});  // (column, k) key, vertex
    tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t q) {
      const auto c = cell_of(V.row(which[q]).transpose());
      keyed[q] = {(c[1] * size_[0] + c[0]) * size_[2] + c[2], which[q]};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    offsets_.assign(std::size_t(size_[0] * size_[1] + 1), 0);
    heights_.resize(keyed.size());
    vertices_.resize(keyed.size());
    for (std::size_t q = 0; q < keyed.size(); ++q) {
      ++offsets_[std::size_t(keyed[q].first / size_[2]) + 1];
      heights_[q] = int(keyed[q].first % size_[2]);
      vertices_[q] = keyed[q].second;
    }
    std::partial_sum(offsets_.begin(), offsets_.end(), offsets_.begin());
  }

  // Calls f(vertex) for each vertex in a cube that meets the ball (centre p, radius r): per
  // column, only the heights within the ball's chord above the column's nearest point.
  template <class F>
  void for_each_near_ball(const Eigen::Vector3d& p, double r, F&& f) const {
    const Eigen::Vector3d reach = Eigen::Vector3d::Constant(r);
    if ((p + reach - origin_).minCoeff() < 0 ||
        ((p - reach - origin_).array() / cell_ >= Eigen::Array3d(size_[0], size_[1], size_[2]))
            .any())
      return;
    const auto a = cell_of(p - reach), b = cell_of(p + reach);
    for (long j = a[1]; j <= b[1]; ++j)
      for (long i = a[0]; i <= b[0]; ++i) {
        const std::size_t col = std::size_t(j * size_[0] + i);
        if (offsets_[col] == offsets_[col + 1]) continue;
        // The column's nearest point to p across x and y.
        const double dx = gap(p[0] - origin_[0], i), dy = gap(p[1] - origin_[1], j);
        const double rest = r * r - dx * dx - dy * dy;
        if (rest < 0) continue;
        const double chord = std::sqrt(rest);
        const long k0 = cell_of_axis(p[2] - chord, 2), k1 = cell_of_axis(p[2] + chord, 2);
        const auto first = heights_.begin() + long(offsets_[col]),
                   last = heights_.begin() + long(offsets_[col + 1]);
        for (auto it = std::lower_bound(first, last, int(k0)); it != last && *it <= k1; ++it)
          f(vertices_[std::size_t(it - heights_.begin())]);
      }
  }

 private:
  long cell_of_axis(double x, int a) const {
    return std::clamp(long(std::floor((x - origin_[a]) / cell_)), 0L, size_[std::size_t(a)] - 1);
  }
  std::array<long, 3> cell_of(const Eigen::Vector3d& p) const {
    return {cell_of_axis(p[0], 0), cell_of_axis(p[1], 1), cell_of_axis(p[2], 2)};
  }
  // Distance from offset x to cell c's extent along an axis (0 inside it).
  double gap(double x, long c) const {
    return std::max({double(c) * cell_ - x, x - double(c + 1) * cell_, 0.0});
  }

  double cell_;
  Eigen::Vector3d origin_;
  std::array<long, 3> size_{};
  std::vector<std::size_t> offsets_;  // per column (i + size_x j), into heights_ / vertices_
  std::vector<int> heights_, vertices_;
};

// A vertex inside ball `sample`, `depth` short of its sphere.
struct Push {
  int vertex;
  int sample;
  double depth;
};

// A vertex counts as inside a ball when deeper than this many spacings: one pushed onto a
// sphere stays put.
constexpr double kInside = 1e-9;
// Vertices are indexed in cubes of this many spacings (1 and 3 were slower on bunny 256^3).
constexpr double kIndexCell = 2;

// For each vertex of `which` inside at least one ball, the ball it enters deepest (ties: the
// lower sample), as the displacement onto that ball's sphere; zero elsewhere.
PointMatrix deepest_pushes(const PointMatrix& V, const std::vector<int>& which,
                           const PointMatrix& points, const Eigen::VectorXd& values,
                           double spacing) {
  const VertexColumns columns(V, which, kIndexCell * spacing);
  const double inside = kInside * spacing;
  constexpr Eigen::Index kBlock = 4096;
  const Eigen::Index n = points.rows(), blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<Push>> found(static_cast<std::size_t>(blocks));
  tbb::parallel_for(Eigen::Index(0), blocks, [&](Eigen::Index b) {
    auto& out = found[std::size_t(b)];
    for (Eigen::Index s = b * kBlock; s < std::min(n, (b + 1) * kBlock); ++s) {
      const double r = std::abs(values[s]);
      if (!(r > 0)) continue;
      const Eigen::Vector3d p = points.row(s).transpose();
      columns.for_each_near_ball(p, r, [&](int v) {
        const double d2 = (V.row(v).transpose() - p).squaredNorm();
        if (!(d2 < r * r && d2 > 0)) return;
        const double depth = r - std::sqrt(d2);
        if (depth > inside) out.push_back({v, int(s), depth});
      });
    }
  });
  std::vector<Push> best(std::size_t(V.rows()), Push{-1, -1, 0.0});
  for (const auto& block : found)
    for (const Push& q : block) {
      Push& b = best[std::size_t(q.vertex)];
      if (b.vertex < 0 || q.depth > b.depth || (q.depth == b.depth && q.sample < b.sample)) b = q;
    }
  PointMatrix moves = PointMatrix::Zero(V.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), V.rows(), [&](Eigen::Index v) {
    const Push& b = best[std::size_t(v)];
    if (b.vertex < 0) return;
    const Eigen::Vector3d p = points.row(b.sample).transpose();
    const Eigen::Vector3d from = V.row(v).transpose() - p;
    const double r = std::abs(values[b.sample]);
    moves.row(v) = (p + from * (r / from.norm()) - V.row(v).transpose()).transpose();
  });
  return moves;
}

Eigen::Vector3d triangle_normal(const PointMatrix& V, const TriangleMatrix& F, Eigen::Index t) {
  const Eigen::Vector3d a = V.row(F(t, 0)).transpose();
  return (V.row(F(t, 1)).transpose() - a).cross(V.row(F(t, 2)).transpose() - a);
}

// Scales each vertex's move (factor 1, halved, then 0) until no triangle's normal turns by more
// than the allowed angle; returns the vertices held back.
long hold_back_turning_triangles(const Mesh& mesh, const PointMatrix& moves,
                                 std::vector<double>& factor, const CarvingOptions& options) {
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  std::vector<Eigen::Index> moving;  // triangles with a moving vertex
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    if (factor[std::size_t(F(t, 0))] > 0 || factor[std::size_t(F(t, 1))] > 0 ||
        factor[std::size_t(F(t, 2))] > 0)
      moving.push_back(t);
  std::vector<Eigen::Vector3d> before(moving.size());
  for (std::size_t q = 0; q < moving.size(); ++q) before[q] = triangle_normal(V, F, moving[q]);
  const double min_cos = std::cos(options.max_turn_degrees * M_PI / 180);
  std::vector<char> turned(moving.size());
  std::vector<char> held(std::size_t(V.rows()), 0);
  for (int round = 0;; ++round) {
    tbb::parallel_for(std::size_t(0), moving.size(), [&](std::size_t q) {
      const Eigen::Index t = moving[q];
      Eigen::Matrix3d corners;
      for (int c = 0; c < 3; ++c) {
        const int v = F(t, c);
        corners.col(c) = (V.row(v) + factor[std::size_t(v)] * moves.row(v)).transpose();
      }
      const Eigen::Vector3d after =
          (corners.col(1) - corners.col(0)).cross(corners.col(2) - corners.col(0));
      turned[q] = !(before[q].dot(after) >= min_cos * before[q].norm() * after.norm());
    });
    bool any = false;
    for (std::size_t q = 0; q < moving.size(); ++q) {
      if (!turned[q]) continue;
      for (int c = 0; c < 3; ++c) {
        const std::size_t v = std::size_t(F(moving[q], c));
        if (factor[v] == 0) continue;
        factor[v] = round < options.halvings ? factor[v] / 2 : 0;
        held[v] = 1;
        any = true;
      }
    }
    if (!any) break;
  }
  return long(std::count(held.begin(), held.end(), 1));
}

}  // namespace

CarvingStats carve_mesh(Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values,
                        double spacing, const CarvingOptions& options) {
  if (points.rows() != values.size())
    throw Error("sphere carving: " + std::to_string(points.rows()) + " points but " +
                std::to_string(values.size()) + " values");
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error("sphere carving: the spacing must be positive and finite");
  if (!values.allFinite() || !points.allFinite())
    throw Error("sphere carving: the samples must be finite");
  if (options.passes < 0 || options.halvings < 0 || !(options.max_turn_degrees >= 0) ||
      !(options.max_turn_degrees <= 180))
    throw Error("sphere carving: passes and halvings must be >= 0, the turn in [0, 180] degrees");
  CarvingStats stats;
  PointMatrix& V = mesh.vertices;
  if (V.rows() == 0 || points.rows() == 0) return stats;
  const PointMatrix start = V;
  // Only a vertex that moved can have entered a ball: later rounds look at those alone.
  std::vector<int> candidates(std::size_t(V.rows()));
  std::iota(candidates.begin(), candidates.end(), 0);
  while (stats.passes < options.passes && !candidates.empty()) {
    ++stats.passes;
    const PointMatrix moves = deepest_pushes(V, candidates, points, values, spacing);
    std::vector<double> factor(std::size_t(V.rows()));
    for (Eigen::Index v = 0; v < V.rows(); ++v)
      factor[std::size_t(v)] = moves.row(v).squaredNorm() > 0 ? 1.0 : 0.0;
    if (std::none_of(factor.begin(), factor.end(), [](double f) { return f > 0; })) break;
    stats.held_back += hold_back_turning_triangles(mesh, moves, factor, options);
    candidates.clear();
    for (Eigen::Index v = 0; v < V.rows(); ++v)
      if (factor[std::size_t(v)] > 0) {
        V.row(v) += factor[std::size_t(v)] * moves.row(v);
        candidates.push_back(int(v));
      }
  }
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const double d = (V.row(v) - start.row(v)).norm();
    if (d > 0) ++stats.vertices_moved;
    stats.largest_move = std::max(stats.largest_move, d);
  }
  return stats;
}

}  // namespace sdfcontour
