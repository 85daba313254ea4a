#include "sdfcontour/reconstruction/adaptivity.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "reconstruction/point_cubes.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
using Vertex = SurfaceMesh::Vertex_index;
namespace SMS = CGAL::Surface_mesh_simplification;

// Sum over planes (n, d) of w (n.x + d)^2 = x^T A x + 2 b.x + c.
struct Quadric {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double c = 0;

  void add_plane(const Eigen::Vector3d& n, const Eigen::Vector3d& p, double w) {
    const double d = -n.dot(p);
    A += w * n * n.transpose();
    b += w * d * n;
    c += w * d * d;
  }
  Quadric operator+(const Quadric& o) const {
    Quadric q;
    q.A = A + o.A, q.b = b + o.b, q.c = c + o.c;
    return q;
  }
  double at(const Eigen::Vector3d& x) const {
    return std::max(0.0, x.dot(A * x) + 2 * b.dot(x) + c);
  }
  // The minimiser nearest `centre` along the directions the planes leave free (eigenvalues
  // under kFree of the largest): a plane keeps its vertex, a crease or corner draws it. Only
  // directions that no curvature fixes are left free: with 1e-3, merged vertices slid along
  // gently curved regions (bunny 128^3, TOL 0.1: L1 1.28x TOL 0's against 1.13x with 1e-6).
  Eigen::Vector3d minimiser(const Eigen::Vector3d& centre) const {
    constexpr double kFree = 1e-6;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(A);
    const Eigen::Vector3d lambda = eig.eigenvalues();
    const Eigen::Matrix3d U = eig.eigenvectors();
    const Eigen::Vector3d r = -(A * centre + b);
    Eigen::Vector3d x = centre;
    for (int j = 0; j < 3; ++j)
      if (lambda[j] > kFree * lambda[2] && lambda[j] > 0)
        x += U.col(j) * (U.col(j).dot(r) / lambda[j]);
    return x;
  }
};

Eigen::Vector3d vec(const K::Point_3& p) {
  return {p.x(), p.y(), p.z()};
}

// Each point's nearest vertex within a spacing (-1 if none; ties: the lower vertex).
std::vector<int> nearest_vertices(const PointMatrix& V, const PointMatrix& P, double h) {
  const detail::PointCubes cubes(V, h);
  std::vector<int> nearest(std::size_t(P.rows()), -1);
  tbb::parallel_for(Eigen::Index(0), P.rows(), [&](Eigen::Index i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    double best = h * h;
    cubes.for_each_near(p, [&](int v) {
      const double d = (V.row(v).transpose() - p).squaredNorm();
      if (d < best || (d == best && v < nearest[std::size_t(i)]))
        best = d, nearest[std::size_t(i)] = v;
    });
  });
  return nearest;
}

// A contact point stands for about a cell's h^2 of surface, a triangle for its area over h^2:
// weighed alike. The triangles' planes keep the merged mesh near the unmerged one where points
// are few; at a tenth of this weight, merges went there first (bunny and wingnut 128^3 at equal
// triangle counts: L1 1.18x and 1.18x TOL 0's with 0.1 against 1.04x and 1.09x with 1).
constexpr double kFaceWeight = 1.0;

// The quadrics of the mesh's vertices: the planes of the points nearest them, and of their
// triangles.
std::vector<Quadric> vertex_quadrics(const Mesh& mesh, const PointMatrix& points,
                                     const PointMatrix& normals, double h) {
  std::vector<Quadric> q(std::size_t(mesh.vertices.rows()));
  const std::vector<int> nearest = nearest_vertices(mesh.vertices, points, h);
  for (Eigen::Index i = 0; i < points.rows(); ++i)  // in row order: the same sums every run
    if (nearest[std::size_t(i)] >= 0)
      q[std::size_t(nearest[std::size_t(i)])].add_plane(normals.row(i).transpose(),
                                                        points.row(i).transpose(), 1.0);

  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.triangles(t, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.row(mesh.triangles(t, 2)).transpose();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() == 0) continue;
    const double w = kFaceWeight * n.norm() / 6 / (h * h);
    for (int k = 0; k < 3; ++k)
      q[std::size_t(mesh.triangles(t, k))].add_plane(n.normalized(), a, w);
  }
  return q;
}

// The policies over one quadric per vertex (indexed by the Surface_mesh's vertex index).
struct QuadricPolicies {
  std::vector<Quadric>* quadrics;
  double h;
  const std::vector<char>* frozen;  // vertices no merge may move

  template <class Profile>
  Quadric merged(const Profile& profile) const {
    return (*quadrics)[std::size_t(profile.v0())] + (*quadrics)[std::size_t(profile.v1())];
  }
};

struct QuadricPlacement {
  QuadricPolicies policies;
  template <class Profile>
  boost::optional<K::Point_3> operator()(const Profile& profile) const {
    const std::vector<char>& frozen = *policies.frozen;
    if (frozen[std::size_t(profile.v0())] || frozen[std::size_t(profile.v1())]) return boost::none;
    const Eigen::Vector3d mid = (vec(profile.p0()) + vec(profile.p1())) / 2;
    const Eigen::Vector3d x = policies.merged(profile).minimiser(mid);
    // A minimiser far from the edge extrapolates (nearly parallel planes): not merged.
    if (!x.allFinite() || (x - mid).norm() > 2 * policies.h) return boost::none;
    return K::Point_3(x[0], x[1], x[2]);
  }
};

// The summed squared plane distances at the placement, in spacings squared.
struct QuadricCost {
  QuadricPolicies policies;
  template <class Profile>
  boost::optional<double> operator()(const Profile& profile,
                                     const boost::optional<K::Point_3>& placement) const {
    if (!placement) return boost::none;
    // Summed, not averaged: a region merges while all its points together stay this close.
    return policies.merged(profile).at(vec(*placement)) / (policies.h * policies.h);
  }
};

struct ToleranceStop {
  double squared;
  template <class Profile>
  bool operator()(const double& cost, const Profile&, std::size_t, std::size_t) const {
    return cost > squared;
  }
};

// Refuses a placement that flips or turns a triangle of the edge's star by more than the bound.
struct NormalTurnFilter {
  double min_cosine;
  template <class Profile>
  boost::optional<K::Point_3> operator()(const Profile& profile,
                                         boost::optional<K::Point_3> placement) const {
    if (!placement) return placement;
    const Eigen::Vector3d x = vec(*placement);
    for (const auto& t : profile.triangles()) {
      const Eigen::Vector3d a = vec(get(profile.vertex_point_map(), t.v0));
      const Eigen::Vector3d b = vec(get(profile.vertex_point_map(), t.v1));
      const Eigen::Vector3d c = vec(get(profile.vertex_point_map(), t.v2));
      // The triangles of the two faces that vanish hold both ends of the edge.
      const bool has0 = t.v0 == profile.v0() || t.v1 == profile.v0() || t.v2 == profile.v0();
      const bool has1 = t.v0 == profile.v1() || t.v1 == profile.v1() || t.v2 == profile.v1();
      if (has0 && has1) continue;
      auto moved = [&](Vertex v, const Eigen::Vector3d& p) {
        return v == profile.v0() || v == profile.v1() ? x : p;
      };
      const Eigen::Vector3d before = (b - a).cross(c - a);
      const Eigen::Vector3d A = moved(t.v0, a), B = moved(t.v1, b), C = moved(t.v2, c);
      const Eigen::Vector3d after = (B - A).cross(C - A);
      const double norms = before.norm() * after.norm();
      if (!(norms > 0) || before.dot(after) < min_cosine * norms) return boost::none;
    }
    return placement;
  }
};

// Keeps each surviving vertex's quadric the sum of those it merged.
struct MergeVisitor : SMS::Edge_collapse_visitor_base<SurfaceMesh> {
  std::vector<Quadric>* quadrics;
  long* merges;
  template <class Profile>
  void OnCollapsed(const Profile& profile, Vertex kept) {
    (*quadrics)[std::size_t(kept)] =
        (*quadrics)[std::size_t(profile.v0())] + (*quadrics)[std::size_t(profile.v1())];
    ++*merges;
  }
};

// The mesh merged by CGAL's edge collapse, no merge moving a `frozen` vertex; `source` receives
// each output vertex's index in `mesh`.
Mesh collapse(const Mesh& mesh, std::vector<Quadric> quadrics, double h, double tolerance,
              double max_normal_turn, const std::vector<char>& frozen, std::vector<int>& source,
              long& merges) {
  SurfaceMesh sm;
  std::vector<Vertex> vertex(std::size_t(mesh.vertices.rows()));
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    vertex[std::size_t(v)] =
        sm.add_vertex(K::Point_3(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    if (sm.add_face(vertex[std::size_t(mesh.triangles(t, 0))],
                    vertex[std::size_t(mesh.triangles(t, 1))],
                    vertex[std::size_t(mesh.triangles(t, 2))]) == SurfaceMesh::null_face())
      throw Error("adaptivity: the mesh is not 2-manifold and oriented");
  const QuadricPolicies policies{&quadrics, h, &frozen};
  MergeVisitor visitor;
  visitor.quadrics = &quadrics;
  visitor.merges = &merges;
  const double pi = std::acos(-1.0);
  SMS::edge_collapse(sm, ToleranceStop{tolerance * tolerance},
                     CGAL::parameters::get_cost(QuadricCost{policies})
                         .get_placement(QuadricPlacement{policies})
                         .filter(NormalTurnFilter{std::cos(max_normal_turn * pi / 180)})
                         .visitor(visitor));
  // Surface_mesh keeps the indices of the vertices added (removed ones are skipped).
  std::vector<int> out_index(std::size_t(mesh.vertices.rows()), -1);
  source.clear();
  for (Vertex v : sm.vertices()) {
    out_index[std::size_t(v)] = int(source.size());
    source.push_back(int(v));
  }
  Mesh out;
  out.vertices.resize(Eigen::Index(source.size()), 3);
  for (std::size_t r = 0; r < source.size(); ++r)
    out.vertices.row(Eigen::Index(r)) = vec(sm.point(Vertex(source[r]))).transpose();
  out.triangles.resize(Eigen::Index(sm.number_of_faces()), 3);
  Eigen::Index row = 0;
  for (auto f : sm.faces()) {
    int k = 0;
    for (Vertex v : CGAL::vertices_around_face(sm.halfedge(f), sm))
      out.triangles(row, k++) = out_index[std::size_t(v)];
    ++row;
  }
  return out;
}

// Freezes the vertices of `mesh` (the input) within kFrozenReach spacings of the vertices of
// `merged`'s triangles that cross: returns whether any vertex was newly frozen.
constexpr double kFrozenReach = 3;
// Rounds of freezing at most.
constexpr int kFreezeRounds = 4;
bool freeze_around_crossings(const Mesh& mesh, const Mesh& merged, const std::vector<int>& source,
                             double h, std::vector<char>& frozen) {
  const auto pairs = self_intersecting_triangles(merged);
  if (pairs.empty()) return false;
  std::vector<char> crossing(std::size_t(merged.vertices.rows()), 0);
  for (const auto& [s, t] : pairs)
    for (int k = 0; k < 3; ++k)
      crossing[std::size_t(merged.triangles(s, k))] =
          crossing[std::size_t(merged.triangles(t, k))] = 1;
  const detail::PointCubes cubes(mesh.vertices, kFrozenReach * h);
  bool changed = false;
  for (std::size_t v = 0; v < crossing.size(); ++v) {
    if (!crossing[v]) continue;
    changed |= !frozen[std::size_t(source[v])];
    frozen[std::size_t(source[v])] = 1;
    const Eigen::Vector3d p = merged.vertices.row(Eigen::Index(v)).transpose();
    cubes.for_each_near(p, [&](int u) {
      if (!frozen[std::size_t(u)] &&
          (mesh.vertices.row(u).transpose() - p).norm() <= kFrozenReach * h)
        frozen[std::size_t(u)] = 1, changed = true;
    });
  }
  return changed;
}

}  // namespace

Mesh adapt_mesh(const Mesh& mesh, const PointMatrix& points, const PointMatrix& normals,
                double spacing, const AdaptivityOptions& options, AdaptivityStats* stats) {
  if (points.rows() != normals.rows())
    throw Error("adaptivity: " + std::to_string(points.rows()) + " points but " +
                std::to_string(normals.rows()) + " normals");
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error("adaptivity: the spacing must be positive");
  if (!(options.tolerance >= 0 && options.tolerance <= 10))
    throw Error("adaptivity: the tolerance must lie in [0, 10] spacings");
  if (!(options.max_normal_turn > 0 && options.max_normal_turn <= 180))
    throw Error("adaptivity: the normal turn must lie in (0, 180] degrees");
  AdaptivityStats s;
  s.triangles_before = s.triangles_after = long(mesh.triangles.rows());
  if (options.tolerance == 0 || mesh.triangles.rows() == 0) {
    if (stats) *stats = s;
    return mesh;
  }
  const std::vector<Quadric> quadrics = vertex_quadrics(mesh, points, normals, spacing);
  // Merges that make the mesh cross itself are undone by merging again with the vertices around
  // the crossings frozen: the input's own triangles stay there.
  std::vector<char> frozen(std::size_t(mesh.vertices.rows()), 0);
  std::vector<int> source(frozen.size());
  // The input's own crossings (the cube's at 128^3) stay as they are, frozen from the start, so
  // that the rounds below chase only new ones.
  for (std::size_t v = 0; v < source.size(); ++v) source[v] = int(v);
  freeze_around_crossings(mesh, mesh, source, spacing, frozen);
  Mesh out;
  for (int round = 0;; ++round) {
    s.merges = 0;
    out = collapse(mesh, quadrics, spacing, options.tolerance, options.max_normal_turn, frozen,
                   source, s.merges);
    if (round == kFreezeRounds || !freeze_around_crossings(mesh, out, source, spacing, frozen))
      break;
    ++s.freeze_rounds;
  }
  s.triangles_after = long(out.triangles.rows());
  if (stats) *stats = s;
  return out;
}

}  // namespace sdfcontour
