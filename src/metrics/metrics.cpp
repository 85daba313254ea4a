#include "sdfcontour/metrics/metrics.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

namespace sdfcontour {

namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

K::Point_3 point(const PointMatrix& m, Eigen::Index i) {
  return {m(i, 0), m(i, 1), m(i, 2)};
}

}  // namespace

PointMatrix sample_surface(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  const Eigen::Index f = mesh.triangles.rows();
  if (f == 0) throw Error("cannot sample a mesh without triangles");
  std::vector<double> cumulative(static_cast<std::size_t>(f));
  double total = 0;
  for (Eigen::Index t = 0; t < f; ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                          b = mesh.vertices.row(mesh.triangles(t, 1)),
                          c = mesh.vertices.row(mesh.triangles(t, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative[std::size_t(t)] = total;
  }
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  PointMatrix out(Eigen::Index(count), 3);
  for (std::size_t s = 0; s < count; ++s) {
    const double pick = uniform() * total;
    const Eigen::Index t = std::min<Eigen::Index>(
        f - 1, Eigen::Index(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                            cumulative.begin()));
    double u = uniform(), v = uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;  // fold the square onto the triangle
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0)),
                          b = mesh.vertices.row(mesh.triangles(t, 1)),
                          c = mesh.vertices.row(mesh.triangles(t, 2));
    out.row(Eigen::Index(s)) = (a + u * (b - a) + v * (c - a)).transpose();
  }
  return out;
}

Eigen::VectorXd point_mesh_distances(const PointMatrix& points, const Mesh& mesh) {
  std::vector<Triangle> triangles;
  triangles.reserve(std::size_t(mesh.triangles.rows()));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    triangles.emplace_back(point(mesh.vertices, mesh.triangles(t, 0)),
                           point(mesh.vertices, mesh.triangles(t, 1)),
                           point(mesh.vertices, mesh.triangles(t, 2)));
  if (triangles.empty()) throw Error("cannot measure distances to a mesh without triangles");
  // One of each triangle and one hint per point: a repeated triangle changes no distance but
  // every query near it visits each copy, and CGAL's kd-tree of hints recursed past the stack on
  // a mesh whose 83,384 triangles had 50 distinct corners.
  // The first of each set of corners kept, in the mesh's order (the corners sorted once each).
  std::vector<std::pair<std::array<K::Point_3, 3>, std::size_t>> keyed(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    keyed[t] = {{triangles[t][0], triangles[t][1], triangles[t][2]}, t};
    std::sort(keyed[t].first.begin(), keyed[t].first.end());
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<char> repeated(triangles.size(), 0);
  for (std::size_t i = 1; i < keyed.size(); ++i)
    repeated[keyed[i].second] = keyed[i].first == keyed[i - 1].first;
  std::size_t kept = 0;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    if (!repeated[t]) triangles[kept++] = triangles[t];
  triangles.resize(kept);
  Tree tree(triangles.begin(), triangles.end());
  std::vector<Tree::Point_and_primitive_id> hints;
  hints.reserve(triangles.size());
  for (auto t = triangles.cbegin(); t != triangles.cend(); ++t) hints.emplace_back((*t)[0], t);
  std::sort(hints.begin(), hints.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  hints.erase(std::unique(hints.begin(), hints.end(),
                          [](const auto& a, const auto& b) { return a.first == b.first; }),
              hints.end());
  tree.accelerate_distance_queries(hints.begin(), hints.end());
  Eigen::VectorXd d(points.rows());
  tbb::parallel_for(Eigen::Index(0), points.rows(), [&](Eigen::Index i) {
    d[i] = std::sqrt(tree.squared_distance(point(points, i)));
  });
  return d;
}

SurfaceDistances surface_distances(const Mesh& a, const Mesh& b, std::size_t samples,
                                   std::uint64_t seed) {
  struct Directed {
    double mean, rms, max;
  };
  auto directed = [&](const Mesh& from, const Mesh& to) {
    const Eigen::VectorXd d = point_mesh_distances(sample_surface(from, samples, seed), to);
    // Only vertices that a triangle uses: a peer may leave unreferenced ones behind.
    std::vector<char> used(std::size_t(from.vertices.rows()), 0);
    for (Eigen::Index f = 0; f < from.triangles.rows(); ++f)
      for (int k = 0; k < 3; ++k) used[std::size_t(from.triangles(f, k))] = 1;
    PointMatrix corners(Eigen::Index(std::count(used.begin(), used.end(), 1)), 3);
    for (Eigen::Index v = 0, at = 0; v < from.vertices.rows(); ++v)
      if (used[std::size_t(v)]) corners.row(at++) = from.vertices.row(v);
    const double vertex_max = point_mesh_distances(corners, to).maxCoeff();
    return Directed{d.mean(), std::sqrt(d.squaredNorm() / double(d.size())),
                    std::max(d.maxCoeff(), vertex_max)};
  };
  const Directed ab = directed(a, b), ba = directed(b, a);
  SurfaceDistances s;
  s.mean_ab = ab.mean, s.mean_ba = ba.mean, s.rms_ab = ab.rms, s.rms_ba = ba.rms, s.max_ab = ab.max,
  s.max_ba = ba.max;
  s.hausdorff = std::max(ab.max, ba.max);
  s.l1 = 0.5 * (ab.mean + ba.mean);
  s.l2 = 0.5 * (ab.rms + ba.rms);
  return s;
}

double hausdorff_distance(const Mesh& a, const Mesh& b, std::size_t samples, std::uint64_t seed) {
  auto directed = [&](const Mesh& from, const Mesh& to) {
    PointMatrix p(from.vertices.rows() + Eigen::Index(samples), 3);
    p << from.vertices, sample_surface(from, samples, seed);
    return point_mesh_distances(p, to).maxCoeff();
  };
  return std::max(directed(a, b), directed(b, a));
}

}  // namespace sdfcontour
