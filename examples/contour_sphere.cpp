// A sphere's signed distances on a 48^3 grid, contoured with GCP and with marching cubes, both
// written as PLY; prints each mesh's size and its largest distance to the true sphere.
//
//   build/contour_sphere [OUT_PREFIX]   (writes OUT_PREFIX_gcp.ply and OUT_PREFIX_mc.ply)
#include <sdfcontour/io/io.h>
#include <sdfcontour/sdfcontour.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const std::string prefix = argc > 1 ? argv[1] : "sphere";
  const int n = 48;
  const double radius = 0.6;
  sdfcontour::Bounds bounds;  // [-1, 1]^3
  std::vector<float> values(std::size_t(n) * n * n);
  const double h = 2.0 / (n - 1);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        values[(std::size_t(i) * n + j) * n + k] =
            float(std::hypot(-1 + i * h, -1 + j * h, -1 + k * h) - radius);
  try {
    for (const std::string method : {"gcp", "mc"}) {
      sdfcontour::GridSettings settings;
      settings.method = method;
      const sdfcontour::Mesh mesh =
          sdfcontour::contour_grid(values.data(), {n, n, n}, bounds, 0.0, settings);
      double worst = 0;
      for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
        worst = std::max(worst, std::abs(mesh.vertices.row(v).norm() - radius));
      sdfcontour::write_mesh(prefix + "_" + method + ".ply", mesh);
      std::printf("%s: %ld vertices, %ld triangles, worst vertex %.2e spacings off the sphere\n",
                  method.c_str(), long(mesh.vertices.rows()), long(mesh.triangles.rows()),
                  worst / h);
    }
  } catch (const sdfcontour::Error& e) {
    std::fprintf(stderr, "contour_sphere: %s\n", e.what());
    return 1;
  }
  return 0;
}
