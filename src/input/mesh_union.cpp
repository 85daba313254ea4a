#include "sdfcontour/input/mesh_union.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Surface_mesh.h>

#include <map>
#include <numeric>
#include <vector>

#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;

// The triangles of `mesh` whose part is `part`, as a CGAL surface mesh.
SurfaceMesh part_mesh(const Mesh& mesh, const std::vector<int>& part_of_face, int part) {
  SurfaceMesh out;
  std::map<int, SurfaceMesh::Vertex_index> vertex;
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f) {
    if (part_of_face[std::size_t(f)] != part) continue;
    SurfaceMesh::Vertex_index v[3];
    for (int k = 0; k < 3; ++k) {
      const int i = mesh.triangles(f, k);
      auto it = vertex.find(i);
      if (it == vertex.end())
        it = vertex
                 .emplace(i, out.add_vertex(K::Point_3(mesh.vertices(i, 0), mesh.vertices(i, 1),
                                                       mesh.vertices(i, 2))))
                 .first;
      v[k] = it->second;
    }
    out.add_face(v[0], v[1], v[2]);
  }
  return out;
}

void append(Mesh& out, const SurfaceMesh& m) {
  const Eigen::Index base = out.vertices.rows();
  std::map<SurfaceMesh::Vertex_index, int> index;
  out.vertices.conservativeResize(base + Eigen::Index(m.number_of_vertices()), 3);
  Eigen::Index next = base;
  for (const auto v : m.vertices()) {
    const auto& p = m.point(v);
    out.vertices.row(next) << p.x(), p.y(), p.z();
    index[v] = int(next++);
  }
  const Eigen::Index first = out.triangles.rows();
  out.triangles.conservativeResize(first + Eigen::Index(m.number_of_faces()), 3);
  Eigen::Index t = first;
  for (const auto f : m.faces()) {
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(m.halfedge(f), m))
      out.triangles(t, k++) = index[v];
    ++t;
  }
}

// CGAL reports a failed assertion on stderr before it throws; a union that fails falls back to
// the parts as they are, so the report is noise on the tool's one-line output.
void silent(const char*, const char*, const char*, int, const char*) {}

// Six times the signed volume that each part bounds (positive: outward faces). CGAL's corefinement
// requires solids bounded outward; an inside-out part made it loop forever.
std::vector<double> part_volumes(const Mesh& mesh, const std::vector<int>& part_of_face,
                                 int parts) {
  std::vector<double> volume(std::size_t(parts), 0.0);
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.triangles(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.row(mesh.triangles(f, 2)).transpose();
    volume[std::size_t(part_of_face[std::size_t(f)])] += a.dot(b.cross(c));
  }
  return volume;
}

int find(std::vector<int>& parent, int x) {
  while (parent[std::size_t(x)] != x)
    x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
  return x;
}

}  // namespace

Mesh union_of_overlapping_parts(const Mesh& mesh, MeshUnionStats* stats) {
  MeshUnionStats s;
  const std::vector<int> label = component_labels(mesh);
  std::vector<int> part_of_face(std::size_t(mesh.triangles.rows()));
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
    part_of_face[std::size_t(f)] = label[std::size_t(mesh.triangles(f, 0))];
  s.parts = connected_components(mesh);
  const auto crossings = self_intersecting_triangles(mesh);
  // Parts that cross themselves cannot be corefined; parts that cross each other are grouped.
  std::vector<char> crosses_itself(std::size_t(s.parts), 0);
  std::vector<int> group(std::size_t(s.parts));
  std::iota(group.begin(), group.end(), 0);
  for (const auto& [a, b] : crossings) {
    const int pa = part_of_face[std::size_t(a)], pb = part_of_face[std::size_t(b)];
    if (pa == pb) {
      crosses_itself[std::size_t(pa)] = 1;
    } else {
      const int ra = find(group, pa), rb = find(group, pb);
      group[std::size_t(std::max(ra, rb))] = std::min(ra, rb);
    }
  }
  const std::vector<double> volume = part_volumes(mesh, part_of_face, s.parts);
  std::map<int, std::vector<int>> members;  // ordered: deterministic output
  for (int p = 0; p < s.parts; ++p) members[find(group, p)].push_back(p);
  Mesh out;
  out.vertices.resize(0, 3);
  out.triangles.resize(0, 3);
  for (const auto& [root, parts] : members) {
    bool can_unite = parts.size() > 1;
    for (int p : parts)
      can_unite = can_unite && !crosses_itself[std::size_t(p)] && volume[std::size_t(p)] > 0;
    SurfaceMesh united = part_mesh(mesh, part_of_face, parts[0]);
    std::size_t merged = 1;
    if (can_unite) {
      for (; merged < parts.size(); ++merged) {
        SurfaceMesh next = part_mesh(mesh, part_of_face, parts[merged]), result;
        bool ok = false;
        const auto error_handler = CGAL::set_error_handler(silent);
        const auto warning_handler = CGAL::set_warning_handler(silent);
        try {
          ok = CGAL::Polygon_mesh_processing::corefine_and_compute_union(united, next, result);
        } catch (const std::exception&) {
          ok = false;  // degenerate input CGAL cannot corefine: the parts stay as they are
        }
        CGAL::set_error_handler(error_handler);
        CGAL::set_warning_handler(warning_handler);
        if (!ok) break;
        united = std::move(result);
        ++s.parts_united;
      }
    }
    append(out, united);
    for (std::size_t i = merged; i < parts.size(); ++i)
      append(out, part_mesh(mesh, part_of_face, parts[i]));
  }
  if (s.parts_united > 0 || !crossings.empty())
    s.crossings_left = long(self_intersecting_triangles(out).size());
  if (stats) *stats = s;
  return s.parts_united > 0 ? out : mesh;
}

}  // namespace sdfcontour
