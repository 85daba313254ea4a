// Contact-point quality of every gradient variant (paper Fig. 3) on SDF grids of real meshes:
// regular and Delaunay triangulations x uniform, volume and James weights, and k-NN least squares
// (k = 6, 18, 26), each with and without +FN (whose fallback tries the regular tets' gradients).
// One CSV row per mesh, resolution and variant: kept points, median and mean |phi(c)| (in grid
// spacings) and n . grad phi(c).
//
// Usage: gradient_variants MESH... --res 32,64 > variants.csv
#include <iostream>
#include <sstream>

#include "sdfcontour/contact_points/contact_point_errors.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/io/io.h"

using namespace sdfcontour;

int main(int argc, char** argv) {
  std::vector<std::string> meshes;
  std::vector<int> resolutions{32, 64};
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--res" && a + 1 < argc) {
      resolutions.clear();
      std::stringstream ss(argv[++a]);
      for (std::string t; std::getline(ss, t, ',');) resolutions.push_back(std::stoi(t));
    } else {
      meshes.push_back(arg);
    }
  }
  std::cout << "mesh,res,variant,fn,samples,kept,median_abs_phi_h,mean_abs_phi_h,median_alignment,"
               "mean_alignment\n";
  for (const auto& path : meshes) {
    const std::string name = path.substr(path.find_last_of('/') + 1,
                                         path.find_last_of('.') - path.find_last_of('/') - 1);
    const MeshSdf sdf(normalize_mesh(read_mesh(path), 0.9));
    for (int n : resolutions) {
      const Grid grid = sample_grid(sdf, n, Bounds{});
      const Samples s = grid.to_samples();
      const double h = grid.spacing()[0];
      const Triangulation regular =
          triangulate(s.points, s.values, {TriangulationKind::Regular, true});
      const Triangulation delaunay =
          triangulate(s.points, s.values, {TriangulationKind::Delaunay, true});
      struct Variant {
        std::string name;
        PointMatrix gradients;
      };
      std::vector<Variant> variants;
      const char* weight_names[3] = {"uniform", "volume", "james"};
      const GradientWeighting weights[3] = {GradientWeighting::Uniform, GradientWeighting::Volume,
                                            GradientWeighting::James};
      for (int t = 0; t < 2; ++t)
        for (int w = 0; w < 3; ++w)
          variants.push_back(
              {std::string(t == 0 ? "reg" : "del") + "/" + weight_names[w],
               vertex_gradients(s.points, s.values, t == 0 ? regular : delaunay, {weights[w]})});
      for (int k : {6, 18, 26})
        variants.push_back({"knn" + std::to_string(k), knn_gradients(s.points, s.values, k)});
      for (const auto& v : variants)
        for (bool fn : {false, true}) {
          ContactPointOptions o;
          o.try_tet_gradients = fn;
          // The filter is the exact power-cell test on the regular triangulation for every
          // variant, so +FN's fallback tries the regular triangulation's tet gradients.
          const ContactPoints cp =
              gradient_contact_points(s.points, s.values, v.gradients, regular, o);
          const ContactPointErrors e = contact_point_errors(cp.points, cp.normals, sdf);
          const Summary value = summarize(e.abs_value), alignment = summarize(e.alignment);
          std::cout << name << "," << n << "," << v.name << "," << (fn ? 1 : 0) << ","
                    << s.points.rows() << "," << cp.size() << "," << value.median / h << ","
                    << value.mean / h << "," << alignment.median << "," << alignment.mean
                    << std::endl;
        }
    }
  }
  return 0;
}
