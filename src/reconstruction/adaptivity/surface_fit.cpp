#include "reconstruction/adaptivity/surface_fit.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "reconstruction/mesh_geometry.h"
#include "reconstruction/nearest_triangles.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour::detail {

namespace {

Eigen::Vector3d corner(const Mesh& m, Eigen::Index t, int k) {
  return m.vertices.row(m.triangles(t, k)).transpose();
}

Eigen::Vector3d unit_normal(const Mesh& m, Eigen::Index t) {
  const Eigen::Vector3d a = corner(m, t, 0);
  const Eigen::Vector3d n = (corner(m, t, 1) - a).cross(corner(m, t, 2) - a);
  const double length = n.norm();
  return length > 0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
}

// The barycentric coordinates of q (on triangle t) clamped to the triangle (thirds on a degenerate
// one).
Eigen::Vector3d clamped_barycentric(const Mesh& m, Eigen::Index t, const Eigen::Vector3d& q) {
  const Eigen::Vector3d l = barycentric(m, t, q).cwiseMax(0.0);
  return l.sum() > 0 ? Eigen::Vector3d(l / l.sum()) : Eigen::Vector3d::Constant(1.0 / 3);
}

// A dense vertex's foot: the merged triangle nearest it and its barycentric coordinates there.
struct Foot {
  int triangle = -1;
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();
};

std::vector<Foot> feet_of(const Mesh& merged, const PointMatrix& samples,
                          const PointMatrix& normals, double h) {
  const NearestTriangles nearest(merged, nullptr, true);
  std::vector<Foot> feet(std::size_t(samples.rows()));
  tbb::parallel_for(Eigen::Index(0), samples.rows(), [&](Eigen::Index s) {
    const Eigen::Vector3d p = samples.row(s).transpose();
    const NearestTriangles::Hit hit = nearest.closest(p);
    if (hit.triangle < 0 || (hit.point - p).norm() > h) return;
    // Another sheet (a thin part's far side) is not this sample's surface.
    if (unit_normal(merged, hit.triangle).dot(normals.row(s).transpose()) < 0.5) return;
    Foot& f = feet[std::size_t(s)];
    f.triangle = hit.triangle;
    f.weights = clamped_barycentric(merged, hit.triangle, hit.point);
  });
  return feet;
}

// For each merged vertex, the (sample, corner) pairs whose feet it carries, ascending.
struct Carried {
  std::vector<long> first;                   // per vertex, into `entries`
  std::vector<std::pair<int, int>> entries;  // (sample, corner)
};

Carried carried_samples(const Mesh& merged, const std::vector<Foot>& feet) {
  Carried c;
  c.first.assign(std::size_t(merged.vertices.rows()) + 1, 0);
  for (const Foot& f : feet)
    if (f.triangle >= 0)
      for (int k = 0; k < 3; ++k) ++c.first[std::size_t(merged.triangles(f.triangle, k)) + 1];
  for (std::size_t v = 1; v < c.first.size(); ++v) c.first[v] += c.first[v - 1];
  c.entries.resize(std::size_t(c.first.back()));
  std::vector<long> next(c.first.begin(), c.first.end() - 1);
  for (std::size_t s = 0; s < feet.size(); ++s)  // in sample order: each run stays ascending
    if (feet[s].triangle >= 0)
      for (int k = 0; k < 3; ++k)
        c.entries[std::size_t(next[std::size_t(merged.triangles(feet[s].triangle, k))]++)] = {
            int(s), k};
  return c;
}

// The median |offset| of the samples with a foot (0 if none).
double median_offset(const std::vector<Foot>& feet, const std::vector<double>& offset) {
  std::vector<double> a;
  for (std::size_t s = 0; s < feet.size(); ++s)
    if (feet[s].triangle >= 0) a.push_back(std::abs(offset[s]));
  if (a.empty()) return 0;
  std::nth_element(a.begin(), a.begin() + std::ptrdiff_t(a.size() / 2), a.end());
  return a[a.size() / 2];
}

// The fit of `merged` to `samples` (n x 3) with unit `normals` (n x 3).
long fit_to_samples(Mesh& merged, const PointMatrix& samples, const PointMatrix& normals,
                    const std::vector<char>& fixed, double h, const SurfaceFitOptions& options) {
  if (fixed.size() != std::size_t(merged.vertices.rows()))
    throw InternalError("surface fit: one fixed flag per vertex expected");
  if (merged.triangles.rows() == 0 || samples.rows() == 0) return 0;
  const PointMatrix start = merged.vertices;
  const std::vector<Foot> feet = feet_of(merged, samples, normals, h);
  const Carried carried = carried_samples(merged, feet);
  // A vertex that solved alone for its samples' offsets, with its neighbours held, moves about
  // twice as far as the shift they need together (the barycentric weights' mean over their
  // mean square, 1/3 over 1/6): half the step.
  constexpr double kDamping = 0.5;
  // Along the directions that no sample fixes, a vertex stays (a tenth of the mean weight).
  constexpr double kTangentHold = 0.1;
  const double reach = options.max_move * h;
  // Samples weigh 1 / (1 + (offset / scale)^2), the scale the median |offset| before the first
  // move: a vertex of the unmerged mesh that lies off the surface (next to a crease, where its
  // points were few) then pulls little. Measured at 256^3, TOL 0.03 (L1 without these weights ->
  // with): bunny 2.22e-5 -> 2.06e-5, penguin 1.99e-5 -> 1.89e-5, goathead 2.55e-5 -> 2.43e-5, blub
  // 1.87e-5 -> 1.84e-5; half the median gave the bunny 2.06e-5 too, twice 2.07e-5.
  double scale = 0;
  for (int round = 0; round < options.rounds; ++round) {
    std::vector<Eigen::Vector3d> normal(std::size_t(merged.triangles.rows()));
    tbb::parallel_for(Eigen::Index(0), merged.triangles.rows(),
                      [&](Eigen::Index t) { normal[std::size_t(t)] = unit_normal(merged, t); });
    std::vector<double> offset(feet.size(), 0.0);
    tbb::parallel_for(std::size_t(0), feet.size(), [&](std::size_t s) {
      const Foot& f = feet[s];
      if (f.triangle < 0) return;
      Eigen::Vector3d at = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) at += f.weights[k] * corner(merged, f.triangle, k);
      offset[s] =
          normal[std::size_t(f.triangle)].dot(samples.row(Eigen::Index(s)).transpose() - at);
    });
    if (round == 0) scale = median_offset(feet, offset);
    PointMatrix moved = merged.vertices;
    tbb::parallel_for(Eigen::Index(0), merged.vertices.rows(), [&](Eigen::Index v) {
      const long b = carried.first[std::size_t(v)], e = carried.first[std::size_t(v) + 1];
      if (fixed[std::size_t(v)] || b == e) return;
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      for (long i = b; i < e; ++i) {
        const auto [s, k] = carried.entries[std::size_t(i)];
        const Foot& f = feet[std::size_t(s)];
        const Eigen::Vector3d& n = normal[std::size_t(f.triangle)];
        const double w = f.weights[k];
        const double r = offset[std::size_t(s)];
        const double robust = scale > 0 ? 1 / (1 + (r / scale) * (r / scale)) : 1.0;
        A += robust * w * w * n * n.transpose();
        rhs += robust * w * r * n;
      }
      A += (kTangentHold * A.trace() / 3 + 1e-300) * Eigen::Matrix3d::Identity();
      Eigen::Vector3d x = merged.vertices.row(v).transpose() + kDamping * A.ldlt().solve(rhs);
      const Eigen::Vector3d from = start.row(v).transpose();
      if ((x - from).norm() > reach) x = from + (x - from) * (reach / (x - from).norm());
      if (x.allFinite()) moved.row(v) = x.transpose();
    });
    merged.vertices = std::move(moved);
  }
  revert_self_intersections(merged, start);
  long count = 0;
  for (Eigen::Index v = 0; v < merged.vertices.rows(); ++v)
    count += merged.vertices.row(v) != start.row(v);
  return count;
}

}  // namespace

long fit_merged_vertices(Mesh& merged, const Mesh& dense, const std::vector<char>& fixed, double h,
                         const SurfaceFitOptions& options) {
  return fit_to_samples(merged, dense.vertices, vertex_normals(dense), fixed, h, options);
}

}  // namespace sdfcontour::detail
