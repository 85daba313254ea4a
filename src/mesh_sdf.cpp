#include "sdfcontour/mesh_sdf.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include "sdfcontour/mesh_properties.h"

namespace sdfcontour {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Traits = CGAL::AABB_traits<K, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;
using Side = CGAL::Side_of_triangle_mesh<SurfaceMesh, K, CGAL::Default, Tree>;

void require_closed_mesh(const Mesh& mesh, const std::string& what) {
  if (mesh.triangles.rows() == 0) throw Error(what + " has no triangles");
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
  std::unique_ptr<Side> side;
};

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
  impl_->tree = std::make_unique<Tree>(faces(sm).first, faces(sm).second, sm);
  impl_->tree->accelerate_distance_queries();
  impl_->side = std::make_unique<Side>(*impl_->tree);
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

bool MeshSdf::inside(const Eigen::Vector3d& p) const {
  return (*impl_->side)(K::Point_3(p.x(), p.y(), p.z())) == CGAL::ON_BOUNDED_SIDE;
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
