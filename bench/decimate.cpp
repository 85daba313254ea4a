// The peer for adaptivity (bench/adaptivity.py): a mesh decimated by CGAL's edge collapse with
// Garland-Heckbert plane quadrics to a given triangle count.
//
//   decimate IN.ply OUT.ply TRIANGLES
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <cstdlib>
#include <iostream>
#include <vector>

#include "sdfcontour/io/io.h"

namespace SMS = CGAL::Surface_mesh_simplification;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: decimate IN.ply OUT.ply TRIANGLES\n";
    return 2;
  }
  try {
    const sdfcontour::Mesh in = sdfcontour::read_mesh(argv[1]);
    SurfaceMesh sm;
    std::vector<SurfaceMesh::Vertex_index> v;
    for (Eigen::Index i = 0; i < in.vertices.rows(); ++i)
      v.push_back(
          sm.add_vertex(K::Point_3(in.vertices(i, 0), in.vertices(i, 1), in.vertices(i, 2))));
    for (Eigen::Index t = 0; t < in.triangles.rows(); ++t)
      sm.add_face(v[std::size_t(in.triangles(t, 0))], v[std::size_t(in.triangles(t, 1))],
                  v[std::size_t(in.triangles(t, 2))]);
    const std::size_t target = std::strtoul(argv[3], nullptr, 10);
    // The stop predicate counts edges: a closed triangle mesh has 3/2 edges per triangle.
    SMS::Count_stop_predicate<SurfaceMesh> stop(target * 3 / 2);
    SMS::GarlandHeckbert_plane_policies<SurfaceMesh, K> policies(sm);
    SMS::edge_collapse(
        sm, stop,
        CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
    sm.collect_garbage();
    sdfcontour::Mesh out;
    out.vertices.resize(Eigen::Index(sm.number_of_vertices()), 3);
    for (auto x : sm.vertices())
      out.vertices.row(Eigen::Index(x)) << sm.point(x).x(), sm.point(x).y(), sm.point(x).z();
    out.triangles.resize(Eigen::Index(sm.number_of_faces()), 3);
    Eigen::Index row = 0;
    for (auto f : sm.faces()) {
      int k = 0;
      for (auto x : CGAL::vertices_around_face(sm.halfedge(f), sm))
        out.triangles(row, k++) = int(x);
      ++row;
    }
    sdfcontour::write_mesh(argv[2], out);
  } catch (const std::exception& e) {
    std::cerr << "decimate: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
