// sdfcontour eval: distances between a reconstruction and the ground truth; eval-points: oriented
// points against a ground-truth mesh. Both print JSON.
#include "cli_options.h"
#include "commands.h"
#include "io/file_checks.h"
#include "sdfcontour/contact_points/contact_point_errors.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour::cli {

namespace {

struct EvalArgs {
  std::string recon, gt, output;
  std::size_t samples = 200000;
  std::uint64_t seed = 1;
};

int run_eval(const EvalArgs& a) {
  if (a.samples == 0 || a.samples > 100000000)
    throw Error("--samples must be between 1 and 100000000");
  require_distinct_files({a.recon, a.gt}, {a.output});
  const Mesh recon = read_mesh(a.recon), gt = read_mesh(a.gt);
  const SurfaceDistances d = surface_distances(recon, gt, a.samples, a.seed);
  const MeshTopology t = mesh_topology(recon);
  const int components = connected_components(recon);
  nlohmann::json j;
  j["recon"] = a.recon;
  j["gt"] = a.gt;
  j["samples"] = a.samples;
  j["L_inf"] = d.hausdorff;
  j["L1"] = d.l1;
  j["L2"] = d.l2;
  j["directed"] = {{"recon_to_gt", {{"mean", d.mean_ab}, {"rms", d.rms_ab}, {"max", d.max_ab}}},
                   {"gt_to_recon", {{"mean", d.mean_ba}, {"rms", d.rms_ba}, {"max", d.max_ba}}}};
  j["recon_mesh"] = {{"vertices", recon.vertices.rows()},
                     {"triangles", recon.triangles.rows()},
                     {"closed", t.closed},
                     {"manifold", t.nonmanifold_edges == 0},
                     {"consistently_oriented", t.consistently_oriented},
                     {"components", components},
                     {"euler_characteristic", t.euler_characteristic},
                     {"self_intersections", long(self_intersecting_triangles(recon).size())}};
  if (t.closed) j["recon_mesh"]["genus"] = (2 * long(components) - t.euler_characteristic) / 2;
  write_json(j, a.output);
  return 0;
}

int run_eval_points(const EvalArgs& a) {
  require_distinct_files({a.recon, a.gt}, {a.output});
  const OrientedPoints points = read_oriented_points(a.recon);
  if (points.points.rows() == 0) throw Error("'" + a.recon + "' holds no points to evaluate");
  const MeshSdf sdf(read_mesh(a.gt));
  const ContactPointErrors e = contact_point_errors(points.points, points.normals, sdf);
  auto summary = [](const std::vector<double>& v) {
    const Summary s = summarize(v);
    return nlohmann::json{{"median", s.median}, {"mean", s.mean}, {"p95", s.p95}, {"p05", s.p05}};
  };
  nlohmann::json j;
  j["points"] = a.recon;
  j["gt"] = a.gt;
  j["count"] = points.points.rows();
  j["abs_value"] = summary(e.abs_value);
  j["normal_alignment"] = summary(e.alignment);
  write_json(j, a.output);
  return 0;
}

}  // namespace

Command add_eval_commands(CLI::App& app, Command& eval_points) {
  auto a = std::make_shared<EvalArgs>();
  CLI::App* c = app.add_subcommand(
      "eval", "Distances between a reconstruction and the ground truth, as JSON");
  c->add_option("recon", a->recon, "Reconstructed mesh")->required();
  c->add_option("gt", a->gt, "Ground-truth mesh")->required();
  c->add_option("--samples", a->samples, "Area-uniform samples on each mesh")
      ->capture_default_str();
  c->add_option("--seed", a->seed, "Seed for the samples")->capture_default_str();
  c->add_option("-o,--output", a->output, "Write the JSON here instead of stdout");

  auto p = std::make_shared<EvalArgs>();
  CLI::App* e = app.add_subcommand(
      "eval-points", "Contact points against the ground truth: |phi(c)| and n . grad phi");
  e->add_option("points", p->recon, "Oriented points (PLY x y z nx ny nz)")->required();
  e->add_option("gt", p->gt, "Ground-truth closed mesh")->required();
  e->add_option("-o,--output", p->output, "Write the JSON here instead of stdout");
  eval_points = {e, [p] { return run_eval_points(*p); }};
  return {c, [a] { return run_eval(*a); }};
}

}  // namespace sdfcontour::cli
