// Meshes and oriented points: sampling a mesh's SDF, distances between meshes, Poisson's
// reconstruction, adaptivity's merging, and mesh files.
#include <pybind11/stl.h>

#include <cstdint>

#include "binding/common.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/input/mesh_union.h"
#include "sdfcontour/input/signed_distance.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"

namespace sdfcontour::binding {

namespace {

// The mesh (V, F) merged where flat (adaptivity.h) over the contact points (P, N), `spacing` the
// grid's: (V, F, stats).
py::tuple run_adapt_mesh(const py::array& V, const py::array& F, const py::array& P,
                         const py::array& N, double spacing, double tolerance, int brick_spacings) {
  const Mesh mesh = mesh_from(V, F);
  const PointMatrix points =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(P), "P");
  const PointMatrix normals =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(N), "N");
  AdaptivityOptions options;  // (adapt_mesh checks the sizes, spacing and tolerance)
  options.tolerance = tolerance;
  options.brick_spacings = brick_spacings;
  AdaptivityStats stats;
  Mesh out = run_interruptible([&](std::atomic<bool>&) {
    return adapt_mesh(mesh, points, normals, spacing, options, &stats);
  });
  return py::make_tuple(to_numpy(std::move(out.vertices)), to_numpy(std::move(out.triangles)),
                        adaptivity_stats(stats));
}

py::tuple run_poisson(const py::array& P, const py::array& N, const py::object& W,
                      const py::dict& options) {
  OrientedPoints points;
  points.points =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(P), "P");
  points.normals =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(N), "N");
  if (!W.is_none()) {
    const auto w = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(W);
    if (!w || w.ndim() != 1 || w.shape(0) != points.points.rows())
      throw Error("W must have shape (n,), one weight per point");
    points.weights = Eigen::Map<const Eigen::VectorXd>(w.data(), w.shape(0));
  }
  PoissonOptions o = poisson_options(options);
  PoissonResult r = run_interruptible([points, o](std::atomic<bool>& cancel) mutable {
    o.cancel = &cancel;
    return poisson_reconstruct(points, o);
  });
  return py::make_tuple(to_numpy(std::move(r.mesh.vertices)),
                        to_numpy(std::move(r.mesh.triangles)));
}

// The grid of signed distances of a closed mesh, normalised first as the CLI's `sample` does
// when `scale` > 0 (longest side spanning [-scale, scale], centred); returns (grid, the mesh's
// vertices as sampled).
py::tuple run_sample(const py::array& V, const py::array& F, int resolution,
                     const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                     double scale) {
  if (resolution < 2 || resolution > 1024) throw Error("resolution must be between 2 and 1024");
  Mesh mesh = mesh_from(V, F);
  if (scale > 0) mesh = normalize_mesh(mesh, scale);
  const Bounds bounds = bounds_of(lo, hi);
  Grid grid = run_interruptible([mesh, resolution, bounds](std::atomic<bool>&) {
    require_closed_mesh(mesh, "the mesh");
    const MeshSdf sdf(union_of_overlapping_parts(mesh));
    return sample_grid(sdf, resolution, bounds);
  });
  auto* owned = new Eigen::VectorXd(std::move(grid.values));
  py::capsule owner(owned, [](void* p) { delete static_cast<Eigen::VectorXd*>(p); });
  const py::ssize_t n = resolution, d = sizeof(double);
  return py::make_tuple(py::array_t<double>({n, n, n}, {n * n * d, n * d, d}, owned->data(), owner),
                        to_numpy(std::move(mesh.vertices)));
}

py::dict run_distances(const py::array& V, const py::array& F, const py::array& V_gt,
                       const py::array& F_gt, std::size_t samples, std::uint64_t seed) {
  if (samples == 0 || samples > 100000000) throw Error("samples must be between 1 and 1e8");
  const Mesh recon = mesh_from(V, F), gt = mesh_from(V_gt, F_gt);
  const SurfaceDistances d = run_interruptible([recon, gt, samples, seed](std::atomic<bool>&) {
    return surface_distances(recon, gt, samples, seed);
  });
  const MeshTopology t = mesh_topology(recon);
  py::dict out;
  out["L1"] = d.l1;
  out["L2"] = d.l2;
  out["L_inf"] = d.hausdorff;
  out["recon_to_gt"] =
      py::dict(py::arg("mean") = d.mean_ab, py::arg("rms") = d.rms_ab, py::arg("max") = d.max_ab);
  out["gt_to_recon"] =
      py::dict(py::arg("mean") = d.mean_ba, py::arg("rms") = d.rms_ba, py::arg("max") = d.max_ba);
  out["closed"] = t.closed;
  out["components"] = connected_components(recon);
  return out;
}

py::tuple run_read_mesh(const std::string& path) {
  Mesh mesh = read_mesh(path);
  return py::make_tuple(to_numpy(std::move(mesh.vertices)), to_numpy(std::move(mesh.triangles)));
}

void run_write_mesh(const std::string& path, const py::array& V, const py::array& F, bool ascii) {
  write_mesh(path, mesh_from(V, F), ascii ? PlyFormat::Ascii : PlyFormat::Binary);
}

}  // namespace

void bind_meshes(py::module_& m) {
  m.def(
      "mesh_topology",
      [](const py::array& V, const py::array& F) { return topology_stats(mesh_from(V, F)); },
      py::arg("V"), py::arg("F"));
  m.def("read_mesh", &run_read_mesh, py::arg("path"));
  m.def("write_mesh", &run_write_mesh, py::arg("path"), py::arg("V"), py::arg("F"),
        py::arg("ascii"));
  m.def("adapt_mesh", &run_adapt_mesh, py::arg("V"), py::arg("F"), py::arg("P"), py::arg("N"),
        py::arg("spacing"), py::arg("tolerance"),
        py::arg("brick_spacings") = AdaptivityOptions{}.brick_spacings);
  m.def("poisson", &run_poisson, py::arg("P"), py::arg("N"), py::arg("W"), py::arg("options"));
  m.def("sample", &run_sample, py::arg("V"), py::arg("F"), py::arg("resolution"), py::arg("lo"),
        py::arg("hi"), py::arg("scale"));
  m.def("distances", &run_distances, py::arg("V"), py::arg("F"), py::arg("V_gt"), py::arg("F_gt"),
        py::arg("samples"), py::arg("seed"));
}

}  // namespace sdfcontour::binding
