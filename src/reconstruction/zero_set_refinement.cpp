#include "sdfcontour/reconstruction/zero_set_refinement.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "reconstruction/nearest_triangles.h"
#include "sdfcontour/types.h"

namespace sdfcontour {

namespace {

using CellKey = std::array<long, 3>;

CellKey cell_of(const Eigen::Vector3d& p, double size) {
  return {long(std::floor(p.x() / size)), long(std::floor(p.y() / size)),
          long(std::floor(p.z() / size))};
}

// Catmull-Rom weights of the samples at -1, 0, 1, 2 for t in [0, 1], and their derivatives.
void catmull_rom(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
  dw[1] = 0.5 * (9 * t2 - 10 * t);
  dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
  dw[3] = 0.5 * (3 * t2 - 2 * t);
}

// The shell samples' nearest mesh points and mismatches, sorted by the cell (of side `size`) of
// the point, then by sample: a vertex sums them in the same order however the samples came.
struct ShellHits {
  std::vector<std::pair<CellKey, int>> by_cell;  // (cell of the nearest point, hit)
  PointMatrix nearest;
  std::vector<double> mismatch;
};

ShellHits shell_hits(const Mesh& mesh, const Samples& samples, double h,
                     const ZeroSetRefinementOptions& o) {
  std::vector<int> shell;
  for (Eigen::Index i = 0; i < samples.values.size(); ++i) {
    const double a = std::abs(samples.values[i]);
    if (a >= o.shell_inner * h && a <= o.shell_outer * h && a < o.truncation)
      shell.push_back(int(i));
  }
  ShellHits hits;
  hits.nearest.resize(Eigen::Index(shell.size()), 3);
  hits.mismatch.assign(shell.size(), NAN);
  if (shell.empty() || mesh.triangles.rows() == 0) return hits;
  const detail::NearestTriangles index(mesh, nullptr, shell.size() > 1000);
  tbb::parallel_for(std::size_t(0), shell.size(), [&](std::size_t s) {
    const Eigen::Vector3d p = samples.points.row(shell[s]).transpose();
    const auto hit = index.closest(p);
    hits.nearest.row(Eigen::Index(s)) = hit.point.transpose();
    const double d = (hit.point - p).norm();
    if (d > 0) hits.mismatch[s] = std::abs(std::abs(samples.values[shell[s]]) / d - 1);
  });
  const double size = o.gather_radius * h;
  for (std::size_t s = 0; s < shell.size(); ++s)
    if (std::isfinite(hits.mismatch[s]))
      hits.by_cell.emplace_back(cell_of(hits.nearest.row(Eigen::Index(s)).transpose(), size),
                                int(s));
  std::sort(hits.by_cell.begin(), hits.by_cell.end());
  return hits;
}

}  // namespace

std::vector<double> distance_mismatch(const Mesh& mesh, const Samples& samples, double h,
                                      const ZeroSetRefinementOptions& o) {
  if (!(h > 0) || !(o.gather_radius > 0) || !(o.shell_inner <= o.shell_outer))
    throw Error("distance mismatch: needs a positive spacing and gathering radius");
  const ShellHits hits = shell_hits(mesh, samples, h, o);
  const Eigen::Index n = mesh.vertices.rows();
  std::vector<double> out(std::size_t(n), NAN);
  const double size = o.gather_radius * h, r2 = size * size;
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    const CellKey c = cell_of(p, size);
    double sum = 0;
    int count = 0;
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const CellKey k{c[0] + dx, c[1] + dy, c[2] + dz};
          auto it =
              std::lower_bound(hits.by_cell.begin(), hits.by_cell.end(), std::make_pair(k, -1));
          for (; it != hits.by_cell.end() && it->first == k; ++it) {
            const int s = it->second;
            if ((hits.nearest.row(s).transpose() - p).squaredNorm() > r2) continue;
            sum += hits.mismatch[std::size_t(s)];
            ++count;
          }
        }
    if (count >= o.min_samples) out[std::size_t(v)] = count > 0 ? sum / count : 0.0;
  });
  return out;
}

double grid_truncation(const Truncation& truncation, double value_scale) {
  return std::min(truncation.inside, truncation.outside) / value_scale;
}

bool tricubic_value(const GridView& grid, const Eigen::Vector3d& p, double truncation,
                    double& value, Eigen::Vector3d& gradient) {
  const Eigen::Vector3d h = grid.spacing();
  int base[3];
  double w[3][4], dw[3][4];
  for (int a = 0; a < 3; ++a) {
    const double u = (p[a] - grid.bounds.min[a]) / h[a] - grid.first[a];
    if (!std::isfinite(u)) return false;
    const double f = std::floor(u);
    base[a] = int(f) - 1;
    if (f < 1 || base[a] + 3 > grid.dims[a] - 1) return false;
    catmull_rom(u - f, w[a], dw[a]);
  }
  value = 0;
  gradient.setZero();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) {
        const double s = grid.value(grid.index(base[0] + i, base[1] + j, base[2] + k));
        if (!(std::abs(s) < truncation)) return false;
        value += w[0][i] * w[1][j] * w[2][k] * s;
        gradient.x() += dw[0][i] * w[1][j] * w[2][k] * s;
        gradient.y() += w[0][i] * dw[1][j] * w[2][k] * s;
        gradient.z() += w[0][i] * w[1][j] * dw[2][k] * s;
      }
  gradient = gradient.cwiseQuotient(h);
  return true;
}

long refine_on_zero_set(PointMatrix& V, const std::vector<char>& which, const GridView& grid,
                        const ZeroSetRefinementOptions& o, std::vector<char>* moved) {
  if (which.size() != std::size_t(V.rows()))
    throw Error("zero-set refinement: " + std::to_string(which.size()) + " flags for " +
                std::to_string(V.rows()) + " vertices");
  const double h = grid.spacing().maxCoeff();
  std::vector<char> done(which.size(), 0);
  tbb::parallel_for(Eigen::Index(0), V.rows(), [&](Eigen::Index v) {
    if (!which[std::size_t(v)]) return;
    const Eigen::Vector3d start = V.row(v).transpose();
    Eigen::Vector3d p = start, g;
    double f = 0;
    for (int step = 0; step < o.newton_steps; ++step) {
      if (!tricubic_value(grid, p, o.truncation, f, g)) return;
      const double g2 = g.squaredNorm();
      if (!(g2 > 1e-12)) return;
      p -= (f / g2) * g;
    }
    if (!p.allFinite() || (p - start).norm() > o.max_move * h) return;
    V.row(v) = p.transpose();
    done[std::size_t(v)] = 1;
  });
  if (moved) *moved = done;
  return long(std::count(done.begin(), done.end(), char(1)));
}

ZeroSetRefinementStats refine_where_values_are_no_distances(
    Mesh& mesh, const Samples& samples, const GridView& grid, const ZeroSetRefinementOptions& o,
    const std::vector<char>* fixed, std::vector<char>* moved, std::vector<char>* flagged) {
  ZeroSetRefinementStats stats;
  const double h = grid.spacing().maxCoeff();
  const Eigen::Index n = mesh.vertices.rows();
  std::vector<char> which(std::size_t(n), 0);
  const std::vector<double> mismatch = o.mismatch > 0 ? distance_mismatch(mesh, samples, h, o)
                                                      : std::vector<double>(std::size_t(n), 0.0);
  for (std::size_t v = 0; v < mismatch.size(); ++v) {
    if (!std::isfinite(mismatch[v])) continue;
    ++stats.measured;
    if ((o.mismatch <= 0 || mismatch[v] > o.mismatch) && !(fixed && (*fixed)[v])) {
      which[v] = 1;
      ++stats.flagged;
    }
  }
  if (stats.flagged > 0)
    stats.moved = refine_on_zero_set(mesh.vertices, which, grid, o, moved);
  else if (moved)
    moved->assign(which.size(), 0);
  if (flagged) *flagged = std::move(which);
  return stats;
}

}  // namespace sdfcontour
