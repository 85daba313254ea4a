#include "sdfcontour/contact_points/contact_point_errors.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "metrics/statistics.h"

namespace sdfcontour {

ContactPointErrors contact_point_errors(const PointMatrix& points, const PointMatrix& normals,
                                        const SurfaceReference& reference) {
  if (normals.rows() != points.rows()) throw Error("points and normals differ in count");
  const std::size_t n = std::size_t(points.rows());
  ContactPointErrors e{std::vector<double>(n), std::vector<double>(n)};
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const auto [distance, normal] = reference(points.row(Eigen::Index(i)).transpose());
    e.abs_value[i] = std::abs(distance);
    e.alignment[i] = normals.row(Eigen::Index(i)).normalized().dot(normal.transpose());
  });
  return e;
}

ContactPointErrors contact_point_errors(const PointMatrix& points, const PointMatrix& normals,
                                        const AnalyticShape& sdf) {
  return contact_point_errors(points, normals, [&](const Eigen::Vector3d& p) {
    return std::make_pair(sdf.distance(p), sdf.gradient(p));
  });
}

ContactPointErrors contact_point_errors(const PointMatrix& points, const PointMatrix& normals,
                                        const MeshSdf& mesh) {
  return contact_point_errors(points, normals, [&](const Eigen::Vector3d& p) {
    int triangle = 0;
    const double distance = mesh.unsigned_distance(p, nullptr, &triangle);
    return std::make_pair(distance, mesh.triangle_normal(triangle));
  });
}

Summary summarize(const std::vector<double>& values) {
  if (values.empty()) return {};
  return {quantile(values, 0.5), mean(values), quantile(values, 0.05), quantile(values, 0.95)};
}

}  // namespace sdfcontour
