// sdfcontour: contour signed distance samples into triangle meshes.
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sdfcontour/atomic_file.h"
#include "sdfcontour/builtin_shapes.h"
#include "sdfcontour/io.h"
#include "sdfcontour/npy.h"
#include "sdfcontour/pipeline.h"
#include "sdfcontour/poisson.h"
#include "sdfcontour/statistics.h"

using namespace sdfcontour;

namespace {

Bounds parse_bounds(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string token;
  while (std::getline(ss, token, ',')) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != token.size() || !std::isfinite(x))
      throw Error("--bounds: '" + token + "' is not a finite number");
    v.push_back(x);
  }
  Bounds b;
  if (v.size() == 2) {
    b.min.setConstant(v[0]);
    b.max.setConstant(v[1]);
  } else if (v.size() == 6) {
    b.min = Eigen::Vector3d(v[0], v[1], v[2]);
    b.max = Eigen::Vector3d(v[3], v[4], v[5]);
  } else {
    throw Error("--bounds takes MIN,MAX or XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX");
  }
  for (int a = 0; a < 3; ++a)
    if (!(b.min[a] < b.max[a])) throw Error("--bounds: min must be less than max on every axis");
  return b;
}

struct LoadedInput {
  SdfInput input;
  std::unique_ptr<AnalyticShape> shape;  // for built-in shapes
};

LoadedInput load_input(const std::string& spec, const Bounds& bounds, std::uint64_t seed) {
  LoadedInput loaded;
  if (is_builtin_spec(spec)) {
    const BuiltinSpec b = parse_builtin_spec(spec);
    loaded.shape = make_builtin_shape(b.name);
    if (b.random) {
      loaded.input.samples = sample_random(*loaded.shape, b.count, bounds, seed);
    } else {
      loaded.input.is_grid = true;
      loaded.input.grid = sample_grid(*loaded.shape, b.resolution, bounds);
    }
    return loaded;
  }
  loaded.input = sdf_input_from_array(read_npy(spec), bounds);
  return loaded;
}

// |value| and normal alignment of contact points against an exact SDF.
nlohmann::json contact_point_errors(const ContactPoints& cp, const AnalyticShape& shape,
                                    double spacing) {
  std::vector<double> err, align;
  for (Eigen::Index i = 0; i < cp.points.rows(); ++i) {
    const Eigen::Vector3d c = cp.points.row(i).transpose();
    err.push_back(std::abs(shape.distance(c)));
    align.push_back(cp.normals.row(i).dot(shape.gradient(c).transpose()));
  }
  nlohmann::json j;
  j["abs_value_median"] = quantile(err, 0.5);
  j["abs_value_p95"] = quantile(err, 0.95);
  j["abs_value_mean"] = mean(err);
  j["normal_alignment_median"] = quantile(align, 0.5);
  j["normal_alignment_mean"] = mean(align);
  if (spacing > 0) {
    j["spacing"] = spacing;
    j["abs_value_median_in_spacing"] = quantile(err, 0.5) / spacing;
    j["abs_value_p95_in_spacing"] = quantile(err, 0.95) / spacing;
  }
  return j;
}

// Screened Poisson options, shared by `contour` (gcp, gtcp) and `poisson`.
struct PoissonArgs {
  PoissonOptions options;
  std::string boundary = "neumann";

  void add_to(CLI::App* app) {
    app->add_option("--alpha", options.point_weight,
                    "Screening weight (PoissonRecon's --pointWeight); 0 is plain Poisson")
        ->capture_default_str();
    app->add_option("--depth", options.depth, "Finest octree depth")->capture_default_str();
    app->add_option("--full-depth", options.full_depth, "The octree is complete down to this depth")
        ->capture_default_str();
    app->add_option("--samples-per-node", options.samples_per_node,
                    "Splat each normal where an octree node holds about this many samples")
        ->capture_default_str();
    app->add_option("--scale", options.scale,
                    "Domain = bounding cube of the points enlarged by this factor")
        ->capture_default_str();
    app->add_option("--boundary", boundary,
                    "Boundary condition on the domain cube: neumann or dirichlet")
        ->capture_default_str();
  }
  PoissonOptions resolved() const {
    PoissonOptions o = options;
    if (boundary == "neumann")
      o.boundary = PoissonBoundary::Neumann;
    else if (boundary == "dirichlet")
      o.boundary = PoissonBoundary::Dirichlet;
    else
      throw Error("unknown --boundary '" + boundary + "' (known: neumann, dirichlet)");
    return o;
  }
};

struct ContourArgs {
  std::string input, output, points, method = "gcp", bounds = "-1,1", stats, gradient = "regular",
                                     weights = "james";
  int knn = 18, threads = 0;
  double james_epsilon = GradientOptions{}.james_epsilon,
         tie_tolerance = ContactPointOptions{}.tie_tolerance;
  bool fn = false, quiet = false, ascii = false, serial_triangulation = false;
  std::uint64_t seed = 0;
  PoissonArgs poisson;
};

int run_contour(const ContourArgs& a) {
  if (a.output.empty() && a.points.empty())
    throw Error("nothing to write: give -o OUT and/or --points FILE");
  std::unique_ptr<tbb::global_control> threads;
  if (a.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(a.threads));
  auto say = [&](const std::string& m) {
    if (!a.quiet) std::cerr << "[sdfcontour] " << m << "\n";
  };

  ContourOptions opt;
  opt.method = parse_method(a.method);
  opt.want_mesh = !a.output.empty();
  opt.want_points = !a.points.empty();
  if (a.gradient == "regular")
    opt.gradient_source = GradientSource::Regular;
  else if (a.gradient == "delaunay")
    opt.gradient_source = GradientSource::Delaunay;
  else if (a.gradient == "knn")
    opt.gradient_source = GradientSource::Knn;
  else
    throw Error("unknown --gradient '" + a.gradient + "' (known: regular, delaunay, knn)");
  if (a.weights == "uniform")
    opt.gradient.weighting = GradientWeighting::Uniform;
  else if (a.weights == "volume")
    opt.gradient.weighting = GradientWeighting::Volume;
  else if (a.weights == "james")
    opt.gradient.weighting = GradientWeighting::James;
  else
    throw Error("unknown --weights '" + a.weights + "' (known: uniform, volume, james)");
  opt.knn = a.knn;
  opt.gradient.james_epsilon = a.james_epsilon;
  opt.contact.tie_tolerance = a.tie_tolerance;
  opt.contact.try_tet_gradients = a.fn;
  opt.parallel = !a.serial_triangulation;
  opt.poisson = a.poisson.resolved();
  opt.progress = say;

  const auto t0 = std::chrono::steady_clock::now();
  say("reading " + a.input);
  LoadedInput in = load_input(a.input, parse_bounds(a.bounds), a.seed);
  const double load_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ContourResult r = contour(in.input, in.shape.get(), opt);
  r.stages.insert(r.stages.begin(), {"input", load_seconds});

  const auto tw = std::chrono::steady_clock::now();
  const PlyFormat format = a.ascii ? PlyFormat::Ascii : PlyFormat::Binary;
  if (r.mesh) {
    say("writing " + a.output);
    write_mesh(a.output, *r.mesh, format);
  }
  if (r.contact_points && !a.points.empty()) {
    say("writing " + a.points);
    write_oriented_points(a.points, {r.contact_points->points, r.contact_points->normals}, format);
  }
  r.stages.push_back(
      {"output", std::chrono::duration<double>(std::chrono::steady_clock::now() - tw).count()});

  nlohmann::json j;
  j["input"] = a.input;
  j["method"] = a.method;
  j["samples"] = r.samples;
  if (in.input.is_grid) j["grid"] = in.input.grid.dims;
  if (r.hidden >= 0) j["hidden_samples"] = r.hidden;
  if (r.mesh) {
    j["mesh"] = {{"vertices", r.mesh->vertices.rows()},
                 {"triangles", r.mesh->triangles.rows()},
                 {"file", a.output}};
  }
  if (r.contact_points) {
    const ContactPoints& cp = *r.contact_points;
    nlohmann::json c = {{"kept", cp.size()},
                        {"hidden", cp.hidden},
                        {"zero_gradient", cp.zero_gradient},
                        {"discarded", cp.discarded},
                        {"rescued_fn", cp.rescued},
                        {"file", a.points}};
    if (opt.method != Method::Gtcp) {
      c["gradient"] =
          a.gradient == "knn" ? "knn" + std::to_string(a.knn) : a.gradient + "/" + a.weights;
      c["tie_tolerance"] = a.tie_tolerance;
      c["fn"] = a.fn;
    }
    if (in.shape)
      c["error"] = contact_point_errors(
          cp, *in.shape, in.input.is_grid ? in.input.grid.spacing().maxCoeff() : 0.0);
    j["contact_points"] = c;
  }
  double total = 0;
  nlohmann::json stage_json = nlohmann::json::object();
  for (const auto& s : r.stages) {
    stage_json[s.name] = s.seconds;
    total += s.seconds;
  }
  j["seconds"] = stage_json;
  j["seconds_total"] = total;
  if (!a.stats.empty()) {
    AtomicFile f(a.stats);
    f.stream() << j.dump(2) << "\n";
    f.commit();
  }

  // The short human summary.
  std::cout << "samples " << r.samples;
  if (r.hidden >= 0) std::cout << ", hidden " << r.hidden;
  if (r.contact_points) std::cout << ", contact points kept " << r.contact_points->size();
  if (r.mesh)
    std::cout << ", mesh " << r.mesh->vertices.rows() << " vertices / " << r.mesh->triangles.rows()
              << " triangles";
  std::cout << "\nseconds:" << std::fixed << std::setprecision(3);
  for (const auto& s : r.stages) std::cout << " " << s.name << " " << s.seconds;
  std::cout << " (total " << total << ")" << std::endl;
  return 0;
}

struct PoissonCommandArgs {
  std::string input, output, stats, densities;
  bool quiet = false, ascii = false;
  int threads = 0;
  PoissonArgs poisson;
};

int run_poisson(const PoissonCommandArgs& a) {
  std::unique_ptr<tbb::global_control> threads;
  if (a.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(a.threads));
  PoissonOptions o = a.poisson.resolved();
  if (!a.quiet)
    o.progress = [](const std::string& m) { std::cerr << "[sdfcontour] " << m << "\n"; };
  const auto t0 = std::chrono::steady_clock::now();
  const OrientedPoints points = read_oriented_points(a.input);
  const double read_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PoissonResult r = poisson_reconstruct(points, o);
  write_mesh(a.output, r.mesh, a.ascii ? PlyFormat::Ascii : PlyFormat::Binary);
  if (!a.densities.empty())
    write_npy(a.densities, {std::size_t(r.vertex_density.size())},
              std::vector<double>(r.vertex_density.data(),
                                  r.vertex_density.data() + r.vertex_density.size()));
  nlohmann::json j;
  j["input"] = a.input;
  j["points"] = points.points.rows();
  j["mesh"] = {{"vertices", r.mesh.vertices.rows()},
               {"triangles", r.mesh.triangles.rows()},
               {"file", a.output}};
  j["iso_value"] = r.iso_value;
  j["options"] = {{"alpha", o.point_weight},    {"depth", o.depth},
                  {"full_depth", o.full_depth}, {"samples_per_node", o.samples_per_node},
                  {"scale", o.scale},           {"boundary", a.poisson.boundary}};
  nlohmann::json seconds = {{"read", read_seconds}};
  for (const auto& [name, sec] : r.seconds) seconds[name] = sec;
  j["seconds"] = seconds;
  for (const auto& l : r.levels)
    j["levels"].push_back({{"depth", l.depth},
                           {"cells", l.cells},
                           {"unknowns", l.unknowns},
                           {"iterations", l.iterations},
                           {"relative_residual", l.relative_residual},
                           {"assembly_seconds", l.assembly_seconds},
                           {"solve_seconds", l.solve_seconds}});
  if (!a.stats.empty()) {
    AtomicFile f(a.stats);
    f.stream() << j.dump(2) << "\n";
    f.commit();
  }
  std::cout << "points " << points.points.rows() << ", mesh " << r.mesh.vertices.rows()
            << " vertices / " << r.mesh.triangles.rows() << " triangles, iso-value " << r.iso_value
            << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sdfcontour: contour samples of a signed distance function into a triangle mesh"};
  app.require_subcommand(1);
  ContourArgs a;
  CLI::App* contour = app.add_subcommand(
      "contour", "Contour SDF samples (grid .npy, scattered .npy or builtin:NAME@N)");
  contour
      ->add_option("input", a.input,
                   "Grid .npy of shape (nx,ny,nz), scattered samples .npy of shape (n,4) with rows "
                   "x,y,z,value, "
                   "or a built-in shape builtin:NAME@N (N^3 grid) / builtin:NAME@random:COUNT; "
                   "NAME is one of "
                   "sphere, torus, box, plate, shell, csg")
      ->required();
  contour->add_option("-o,--output", a.output, "Mesh to write (.ply binary by default, or .obj)");
  contour->add_option(
      "--points", a.points,
      "Contact points to write as PLY (x y z nx ny nz): GCP's, or GTCP's for --method gtcp");
  contour->add_option("-m,--method", a.method, "gcp, gtcp, mc, mt-rt or mt-dt")
      ->capture_default_str();
  contour
      ->add_option("--bounds", a.bounds,
                   "Grid bounds (positions of the first and last samples) MIN,MAX or "
                   "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX; also the box for random built-in samples")
      ->capture_default_str();
  contour
      ->add_option("--gradient", a.gradient,
                   "GCP gradients from the regular or delaunay triangulation, or knn least squares")
      ->capture_default_str();
  contour
      ->add_option("--weights", a.weights, "Averaging of tet gradients: uniform, volume or james")
      ->capture_default_str();
  contour->add_option("--knn", a.knn, "k for --gradient knn (the paper uses 6, 18, 26)")
      ->capture_default_str();
  contour
      ->add_option("--james-epsilon", a.james_epsilon,
                   "Regularisation of the James weights' linear system")
      ->capture_default_str();
  contour
      ->add_option("--tie-tolerance", a.tie_tolerance,
                   "Contact point c is discarded only if |c - p_n| < |value_n| - tol * |p_n - p|; "
                   "0 is the strict test")
      ->capture_default_str();
  contour->add_flag(
      "--fn", a.fn,
      "+FN: if the averaged gradient's point is discarded, try each incident tet's gradient");
  contour->add_option("--seed", a.seed, "Seed for builtin:NAME@random:COUNT")
      ->capture_default_str();
  contour->add_option("--threads", a.threads, "Worker threads (0: all cores)")
      ->capture_default_str();
  contour->add_flag("--serial-triangulation", a.serial_triangulation,
                    "Insert points sequentially (same result, slower)");
  contour->add_option(
      "--stats", a.stats,
      "Write a JSON summary (counts, per-stage seconds, contact point errors for built-ins)");
  contour->add_flag("--ascii", a.ascii, "Write ASCII PLY instead of binary");
  contour->add_flag("-q,--quiet", a.quiet, "No progress messages on stderr");
  a.poisson.add_to(contour);

  PoissonCommandArgs pa;
  CLI::App* poisson = app.add_subcommand(
      "poisson", "Screened Poisson reconstruction of an oriented point cloud (PLY x y z nx ny nz)");
  poisson
      ->add_option("input", pa.input, "Oriented points: PLY (ASCII or binary) with x y z nx ny nz")
      ->required();
  poisson->add_option("-o,--output", pa.output, "Mesh to write (.ply or .obj)")->required();
  poisson->add_option(
      "--densities", pa.densities,
      "Write each vertex's estimated sampling density (samples per unit area) as .npy");
  poisson->add_option("--stats", pa.stats,
                      "Write a JSON summary (counts, per-stage seconds, per-depth solver figures)");
  poisson->add_option("--threads", pa.threads, "Worker threads (0: all cores)")
      ->capture_default_str();
  poisson->add_flag("--ascii", pa.ascii, "Write ASCII PLY instead of binary");
  poisson->add_flag("-q,--quiet", pa.quiet, "No progress messages on stderr");
  pa.poisson.add_to(poisson);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (contour->parsed()) return run_contour(a);
    if (poisson->parsed()) return run_poisson(pa);
  } catch (const std::exception& e) {
    std::cerr << "sdfcontour: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
