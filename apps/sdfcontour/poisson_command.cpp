// sdfcontour poisson: oriented points -> a watertight mesh by screened Poisson reconstruction.
#include <iostream>

#include "cli_options.h"
#include "commands.h"
#include "io/atomic_file.h"
#include "io/file_checks.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/io/npy.h"

namespace sdfcontour::cli {

namespace {

struct PoissonCommandArgs {
  std::string input, output, densities;
  RunOptions run;
  PoissonArgs poisson;
};

nlohmann::json summary_json(const PoissonCommandArgs& a, const PoissonOptions& o,
                            const PoissonResult& r, Eigen::Index points, double read_seconds) {
  nlohmann::json j;
  j["input"] = a.input;
  j["points"] = points;
  j["mesh"] = {{"vertices", r.mesh.vertices.rows()},
               {"triangles", r.mesh.triangles.rows()},
               {"file", a.output}};
  j["iso_value"] = r.iso_value;
  j["boundary_fallback"] = r.boundary_fallback;
  j["options"] = {{"alpha", o.point_weight},
                  {"depth", o.depth},
                  {"degree", o.degree},
                  {"full_depth", o.full_depth},
                  {"samples_per_node", o.samples_per_node},
                  {"scale", o.scale},
                  {"boundary", poisson_boundary_name(o.boundary)},
                  {"solver_tolerance", o.solver_tolerance},
                  {"finest_solver_tolerance", o.finest_solver_tolerance}};
  nlohmann::json seconds = {{"read", read_seconds}};
  for (const auto& [name, sec] : r.seconds) seconds[name] = sec;
  j["seconds"] = seconds;
  for (const auto& l : r.levels)
    j["levels"].push_back({{"depth", l.depth},
                           {"cells", l.cells},
                           {"unknowns", l.unknowns},
                           {"iterations", l.iterations},
                           {"relative_residual", l.relative_residual},
                           {"converged", l.converged},
                           {"assembly_seconds", l.assembly_seconds},
                           {"solve_seconds", l.solve_seconds}});
  return j;
}

int run_poisson(const PoissonCommandArgs& a) {
  require_distinct_files({a.input}, {a.output, a.run.stats, a.densities});
  for (const std::string* path : {&a.output, &a.run.stats, &a.densities})
    if (!path->empty()) require_writable(*path);
  OutputBatch outputs;
  const auto threads = a.run.limit_threads();
  PoissonOptions o = a.poisson.resolved();
  o.progress = [&](const std::string& m) { a.run.say(m); };
  const auto t0 = std::chrono::steady_clock::now();
  const OrientedPoints points = read_oriented_points(a.input);
  const double read_seconds = seconds_since(t0);
  PoissonResult r = poisson_reconstruct(points, o);
  require_writable_mesh(r.mesh, "the reconstructed mesh");
  write_mesh(a.output, r.mesh, a.run.ascii ? PlyFormat::Ascii : PlyFormat::Binary);
  if (!a.densities.empty())
    write_npy(a.densities, {std::size_t(r.vertex_density.size())},
              std::vector<double>(r.vertex_density.data(),
                                  r.vertex_density.data() + r.vertex_density.size()));
  if (!a.run.stats.empty())
    write_json(summary_json(a, o, r, points.points.rows(), read_seconds), a.run.stats);
  outputs.commit();
  std::cout << "points " << points.points.rows() << ", mesh " << r.mesh.vertices.rows()
            << " vertices / " << r.mesh.triangles.rows() << " triangles, iso-value " << r.iso_value
            << std::endl;
  return 0;
}

}  // namespace

Command add_poisson_command(CLI::App& app) {
  auto a = std::make_shared<PoissonCommandArgs>();
  CLI::App* c = app.add_subcommand(
      "poisson", "Screened Poisson reconstruction of an oriented point cloud (PLY x y z nx ny nz)");
  c->add_option("input", a->input, "Oriented points: PLY (ASCII or binary) with x y z nx ny nz")
      ->required();
  c->add_option("-o,--output", a->output, "Mesh to write (.ply, .obj, .off or .stl)")->required();
  c->add_option("--densities", a->densities,
                "Write each vertex's estimated sampling density (samples per unit area) as .npy");
  a->run.add_to(c, "Write a JSON summary (counts, per-stage seconds, per-depth solver figures)");
  a->poisson.add_to(c);
  return {c, [a] { return run_poisson(*a); }};
}

}  // namespace sdfcontour::cli
