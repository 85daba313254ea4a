#include "reconstruction/adaptivity/edge_collapse.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <cmath>

namespace sdfcontour::detail {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
using Vertex = SurfaceMesh::Vertex_index;
namespace SMS = CGAL::Surface_mesh_simplification;

Eigen::Vector3d vec(const K::Point_3& p) {
  return {p.x(), p.y(), p.z()};
}

// The policies over one quadric per vertex (indexed by the Surface_mesh's vertex index).
struct QuadricPolicies {
  std::vector<MergeQuadric>* quadrics;
  double h;
  const std::vector<char>* frozen;  // vertices no merge may move

  template <class Profile>
  MergeQuadric merged(const Profile& profile) const {
    return (*quadrics)[std::size_t(profile.v0())] + (*quadrics)[std::size_t(profile.v1())];
  }
};

struct QuadricPlacement {
  QuadricPolicies policies;
  template <class Profile>
  boost::optional<K::Point_3> operator()(const Profile& profile) const {
    const std::vector<char>& frozen = *policies.frozen;
    if (frozen[std::size_t(profile.v0())] || frozen[std::size_t(profile.v1())]) return boost::none;
    // A corner keeps its place; two corners stay two.
    const bool pinned0 = (*policies.quadrics)[std::size_t(profile.v0())].pinned;
    const bool pinned1 = (*policies.quadrics)[std::size_t(profile.v1())].pinned;
    if (pinned0 && pinned1) return boost::none;
    if (pinned0) return profile.p0();
    if (pinned1) return profile.p1();
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
  std::vector<MergeQuadric>* quadrics;
  long* merges;
  template <class Profile>
  void OnCollapsed(const Profile& profile, Vertex kept) {
    (*quadrics)[std::size_t(kept)] =
        (*quadrics)[std::size_t(profile.v0())] + (*quadrics)[std::size_t(profile.v1())];
    ++*merges;
  }
};

}  // namespace

Mesh collapse_edges(const Mesh& mesh, std::vector<MergeQuadric>& quadrics,
                    const std::vector<char>& frozen, const CollapseLimits& limits,
                    std::vector<int>& source, long& merges) {
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
  const QuadricPolicies policies{&quadrics, limits.spacing, &frozen};
  MergeVisitor visitor;
  visitor.quadrics = &quadrics;
  visitor.merges = &merges;
  const double pi = std::acos(-1.0);
  SMS::edge_collapse(sm, ToleranceStop{limits.tolerance * limits.tolerance},
                     CGAL::parameters::get_cost(QuadricCost{policies})
                         .get_placement(QuadricPlacement{policies})
                         .filter(NormalTurnFilter{std::cos(limits.max_normal_turn * pi / 180)})
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

}  // namespace sdfcontour::detail
