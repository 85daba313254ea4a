#include "sdfcontour/input/mesh_sdf.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <optional>
#include <vector>

#include "sdfcontour/input/coordinates.h"
#include "sdfcontour/metrics/mesh_properties.h"

namespace sdfcontour {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Traits = CGAL::AABB_traits<K, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;

void require_closed_mesh(const Mesh& mesh, const std::string& what) {
  if (mesh.triangles.rows() == 0) throw Error(what + " has no triangles");
  require_coordinates(mesh.vertices, what);
  const MeshTopology t = mesh_topology(mesh);
  if (!t.closed)
    throw Error(what + " is not closed (" + std::to_string(t.boundary_edges) + " boundary and " +
                std::to_string(t.nonmanifold_edges) +
                " non-manifold edges); a signed distance needs a closed mesh");
  if (!t.consistently_oriented) throw Error(what + " is not consistently oriented");
}

struct MeshSdf::Impl {
  SurfaceMesh mesh;
  std::vector<Eigen::Vector3d> normals;
  std::unique_ptr<Tree> tree;
};

namespace {

// Rays for the winding number: fixed, far from the axes and from each other, so a run is
// deterministic and a ray rarely grazes an edge of an axis-aligned mesh.
const Eigen::Vector3d kRayDirections[] = {{0.5773, 0.6124, 0.5401},   {-0.3152, 0.8417, 0.4385},
                                          {0.7261, -0.2793, 0.6284},  {-0.6419, -0.5338, 0.5505},
                                          {0.2287, 0.3391, -0.9124},  {-0.8163, 0.4072, -0.4094},
                                          {0.4471, -0.8322, -0.3279}, {-0.1935, -0.2648, -0.9447}};

}  // namespace

MeshSdf::MeshSdf(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  require_closed_mesh(mesh, "the mesh");
  SurfaceMesh& sm = impl_->mesh;
  std::vector<SurfaceMesh::Vertex_index> v;
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
    v.push_back(
        sm.add_vertex(K::Point_3(mesh.vertices(i, 0), mesh.vertices(i, 1), mesh.vertices(i, 2))));
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f) {
    sm.add_face(v[std::size_t(mesh.triangles(f, 0))], v[std::size_t(mesh.triangles(f, 1))],
                v[std::size_t(mesh.triangles(f, 2))]);
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(f, 0)),
                          b = mesh.vertices.row(mesh.triangles(f, 1)),
                          c = mesh.vertices.row(mesh.triangles(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    impl_->normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized())
                                          : Eigen::Vector3d::UnitZ());
  }
  if (sm.number_of_faces() != std::size_t(mesh.triangles.rows()))
    throw Error("the mesh has faces CGAL cannot connect (non-manifold vertices?)");
  // Zero-area triangles hold no point their neighbours do not, and break CGAL's ray tests.
  std::vector<SurfaceMesh::Face_index> solid;
  for (const auto f : faces(sm))
    if (!K::Triangle_3(sm.point(sm.source(sm.halfedge(f))), sm.point(sm.target(sm.halfedge(f))),
                       sm.point(sm.target(sm.next(sm.halfedge(f)))))
             .is_degenerate())
      solid.push_back(f);
  if (solid.empty()) throw Error("the mesh has only zero-area triangles");
  impl_->tree = std::make_unique<Tree>(solid.begin(), solid.end(), sm);
  impl_->tree->accelerate_distance_queries();
}

MeshSdf::~MeshSdf() = default;

double MeshSdf::unsigned_distance(const Eigen::Vector3d& p, Eigen::Vector3d* closest,
                                  int* triangle) const {
  const K::Point_3 q(p.x(), p.y(), p.z());
  const auto hit = impl_->tree->closest_point_and_primitive(q);
  const Eigen::Vector3d c(hit.first.x(), hit.first.y(), hit.first.z());
  if (closest) *closest = c;
  if (triangle) *triangle = int(hit.second);
  return (p - c).norm();
}

std::optional<int> MeshSdf::winding_along(const Eigen::Vector3d& p,
                                          const Eigen::Vector3d& direction) const {
  const K::Point_3 from(p.x(), p.y(), p.z());
  const Eigen::Vector3d far = p + std::max(1.0, p.cwiseAbs().maxCoeff()) * direction;
  const K::Point_3 through(far.x(), far.y(), far.z());
  std::vector<Tree::Primitive_id> hits;
  impl_->tree->all_intersected_primitives(K::Ray_3(from, through), std::back_inserter(hits));
  int winding = 0;
  for (const auto f : hits) {
    const auto h = impl_->mesh.halfedge(f);
    const K::Point_3 &a = impl_->mesh.point(impl_->mesh.source(h)),
                     &b = impl_->mesh.point(impl_->mesh.target(h)),
                     &c = impl_->mesh.point(impl_->mesh.target(impl_->mesh.next(h)));
    // Exact predicates: a ray through an edge or vertex, or in the triangle's plane, is ambiguous.
    const auto side = CGAL::orientation(a, b, c, from);
    if (side == CGAL::COPLANAR || CGAL::orientation(from, through, a, b) == CGAL::COPLANAR ||
        CGAL::orientation(from, through, b, c) == CGAL::COPLANAR ||
        CGAL::orientation(from, through, c, a) == CGAL::COPLANAR)
      return std::nullopt;
    winding += side == CGAL::NEGATIVE ? 1 : -1;  // behind the face: the ray leaves through it
  }
  return winding;
}

bool MeshSdf::inside(const Eigen::Vector3d& p) const {
  for (const Eigen::Vector3d& d : kRayDirections)
    if (const auto w = winding_along(p, d.normalized())) return *w != 0;
  // Every ray grazed an edge: p is on the surface or on a seam of it; its distance decides.
  return false;
}

double MeshSdf::distance(const Eigen::Vector3d& p) const {
  const double d = unsigned_distance(p);
  return inside(p) ? -d : d;
}

Eigen::Vector3d MeshSdf::gradient(const Eigen::Vector3d& p) const {
  Eigen::Vector3d c;
  int t = 0;
  const double d = unsigned_distance(p, &c, &t);
  if (!(d > 0)) return impl_->normals[std::size_t(t)];
  const Eigen::Vector3d away = (p - c) / d;
  return inside(p) ? Eigen::Vector3d(-away) : away;
}

Eigen::Vector3d MeshSdf::triangle_normal(int t) const {
  return impl_->normals[std::size_t(t)];
}

}  // namespace sdfcontour
