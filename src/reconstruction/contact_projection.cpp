#include "sdfcontour/reconstruction/contact_projection.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "pipeline/work_counter.h"
#include "reconstruction/point_cubes.h"

namespace sdfcontour {

namespace {

// Area-weighted vertex normals (unit; zero where the triangles around cancel or there are none).
PointMatrix vertex_normals(const Mesh& mesh) {
  PointMatrix N = PointMatrix::Zero(mesh.vertices.rows(), 3);
  // Serial: the sums' order, hence the result, is fixed.
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const Eigen::RowVector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                             b = mesh.vertices.row(mesh.triangles(t, 1)),
                             c = mesh.vertices.row(mesh.triangles(t, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) N.row(mesh.triangles(t, k)) += n;
  }
  for (Eigen::Index v = 0; v < N.rows(); ++v) {
    const double len = N.row(v).norm();
    N.row(v) = len > 0 ? Eigen::RowVector3d(N.row(v) / len) : Eigen::RowVector3d::Zero();
  }
  return N;
}

void validate(const Mesh& mesh, const PointMatrix& points, const PointMatrix& normals,
              double spacing, const ContactProjectionOptions& o) {
  if (points.rows() != normals.rows())
    throw Error("projection: " + std::to_string(points.rows()) + " points but " +
                std::to_string(normals.rows()) + " normals");
  if (!points.allFinite() || !normals.allFinite() || !mesh.vertices.allFinite())
    throw Error("projection: the points, normals and mesh must be finite");
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error("projection: the spacing must be positive and finite");
  if (!(o.radius > 0) || !std::isfinite(o.radius) || !(o.max_move >= 0) ||
      !std::isfinite(o.max_move) || !(o.normal_agreement >= -1 && o.normal_agreement <= 1) ||
      o.min_points < 6 || !(o.depth_scale >= 0) || !std::isfinite(o.depth_scale) ||
      !(o.max_variance_factor >= 1) || !(o.max_residual >= 0) || !std::isfinite(o.max_residual) ||
      o.robust_rounds < 0 || o.robust_rounds > 10 || !(o.robust_scale > 0) ||
      !std::isfinite(o.robust_scale))
    throw Error(
        "projection: radius must be positive, max_move non-negative, normal_agreement in [-1, 1], "
        "min_points at least 6 (a quadric has six coefficients), depth_scale non-negative, "
        "max_variance_factor at least 1, max_residual non-negative, robust_rounds in [0, 10] and "
        "robust_scale positive");
}

}  // namespace

ContactProjectionStats project_to_contact_points(Mesh& mesh, const PointMatrix& points,
                                                 const PointMatrix& normals,
                                                 const Eigen::VectorXd& depths, double spacing,
                                                 const ContactProjectionOptions& o,
                                                 const std::vector<char>* fixed) {
  validate(mesh, points, normals, spacing, o);
  if (depths.size() != 0 && depths.size() != points.rows())
    throw Error("projection: " + std::to_string(points.rows()) + " points but " +
                std::to_string(depths.size()) + " depths");
  if (fixed && fixed->size() != std::size_t(mesh.vertices.rows()))
    throw Error("projection: one fixed flag per vertex is needed");
  const double inv_depth_scale2 = depths.size() && o.depth_scale > 0
                                      ? 1 / (o.depth_scale * o.depth_scale * spacing * spacing)
                                      : 0;
  ContactProjectionStats stats;
  if (points.rows() == 0 || mesh.vertices.rows() == 0) return stats;
  const double r = o.radius * spacing;
  const detail::PointCubes cubes(points, r);
  const PointMatrix N = vertex_normals(mesh);
  // Gaussian weights exp(-d^2 / (2 sigma^2)), sigma = radius / sqrt(8), d in the tangent plane.
  const double inv_two_sigma2 = 4.0 / (r * r);
  std::vector<double> height(std::size_t(mesh.vertices.rows()), 0.0);
  detail::WorkCounter fitted(o.progress, long(mesh.vertices.rows()));
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
    fitted.add();
    const Eigen::Vector3d n = N.row(v).transpose();
    if (n.squaredNorm() == 0 || (fixed && (*fixed)[std::size_t(v)])) return;
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    // A tangent frame (a, b, n); heights and offsets in spacings keep the system well scaled.
    const Eigen::Vector3d a =
        n.cross(std::abs(n[0]) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY())
            .normalized();
    const Eigen::Vector3d b = n.cross(a);
    // Summed in row order: the same bits whatever the cubes (a brick's points start elsewhere).
    thread_local std::vector<int> near;
    near.clear();
    cubes.for_each_near(p, [&](int i) {
      if ((points.row(i).transpose() - p).squaredNorm() <= r * r) near.push_back(i);
    });
    std::sort(near.begin(), near.end());
    // The agreeing points: (1, x, y, x^2, xy, y^2) in spacings, height z in spacings, weight.
    thread_local std::vector<std::pair<Eigen::Matrix<double, 6, 1>, std::array<double, 2>>> fit;
    fit.clear();
    for (const int i : near) {
      const Eigen::Vector3d d = points.row(i).transpose() - p;
      if (normals.row(i).dot(n.transpose()) <= o.normal_agreement) continue;
      const double x = d.dot(a), y = d.dot(b), z = d.dot(n);
      double w = std::exp(-(x * x + y * y) * inv_two_sigma2);
      if (inv_depth_scale2 > 0) w /= 1 + depths[i] * depths[i] * inv_depth_scale2;
      const double sx = x / spacing, sy = y / spacing;
      Eigen::Matrix<double, 6, 1> row;
      row << 1, sx, sy, sx * sx, sx * sy, sy * sy;
      fit.push_back({row, {z / spacing, w}});
    }
    if (int(fit.size()) < o.min_points) return;
    Eigen::Matrix<double, 6, 1> coefficients;
    for (int round = 0; round <= o.robust_rounds; ++round) {
      Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
      double weight_sum = 0, weighted_z2 = 0;
      for (const auto& [row, zw] : fit) {
        double w = zw[1];
        if (round > 0) {
          const double miss = (zw[0] - row.dot(coefficients)) / o.robust_scale;
          w /= 1 + miss * miss;
        }
        weight_sum += w;
        M.selfadjointView<Eigen::Lower>().rankUpdate(row, w);
        rhs += w * zw[0] * row;
        weighted_z2 += w * zw[0] * zw[0];
      }
      M.triangularView<Eigen::StrictlyUpper>() = M.transpose();
      // A rank-deficient neighbourhood (the points on a line) gives no height: skip it.
      const Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(M);
      if (!lu.isInvertible()) return;
      const Eigen::Matrix<double, 6, 6> inverse = lu.inverse();
      if (inverse(0, 0) * weight_sum > o.max_variance_factor) return;
      coefficients = inverse * rhs;
      // Sum w (z - row.c)^2 = sum w z^2 - c.rhs at the least-squares solution.
      if (round == 0 && o.max_residual > 0 &&
          weighted_z2 - coefficients.dot(rhs) > o.max_residual * o.max_residual * weight_sum)
        return;
    }
    const double z0 = coefficients[0];
    if (std::isfinite(z0) && std::abs(z0) <= o.max_move) height[std::size_t(v)] = z0 * spacing;
  });
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    const double z = height[std::size_t(v)];
    if (z == 0) continue;
    mesh.vertices.row(v) += z * N.row(v);
    ++stats.vertices_moved;
    stats.largest_move = std::max(stats.largest_move, std::abs(z));
  }
  return stats;
}

}  // namespace sdfcontour
