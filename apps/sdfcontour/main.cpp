// sdfcontour: contour signed distance samples into triangle meshes.
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "sdfcontour/atomic_file.h"
#include "sdfcontour/builtin_shapes.h"
#include "sdfcontour/contact_points.h"
#include "sdfcontour/io.h"
#include "sdfcontour/mesh_properties.h"
#include "sdfcontour/mesh_sdf.h"
#include "sdfcontour/mesh_transform.h"
#include "sdfcontour/metrics.h"
#include "sdfcontour/npy.h"
#include "sdfcontour/pipeline.h"
#include "sdfcontour/poisson.h"
#include "sdfcontour/statistics.h"
#include "sdfcontour/vdb.h"

using namespace sdfcontour;

namespace {

// The whole of `text` as a finite number, or nothing.
std::optional<double> parse_finite(const std::string& text) {
  std::size_t used = 0;
  double x = 0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used == 0 || used != text.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

Bounds parse_bounds(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string token;
  while (std::getline(ss, token, ',')) {
    const std::optional<double> x = parse_finite(token);
    if (!x) throw Error("--bounds: '" + token + "' is not a finite number");
    v.push_back(*x);
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
  for (int a = 0; a < 3; ++a) {
    if (!(b.min[a] < b.max[a])) throw Error("--bounds: min must be less than max on every axis");
    if (!std::isfinite(b.max[a] - b.min[a]) || b.max[a] - b.min[a] > 1e150)
      throw Error("--bounds: the box is too large to compute with");
  }
  return b;
}

// Range checks for numeric options: finite and within [lo, hi].
void require_range(const std::string& option, double value, double lo, double hi) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    std::ostringstream m;
    m << option << " must be a finite number between " << lo << " and " << hi << ", got " << value;
    throw Error(m.str());
  }
}

// A mesh is written only if it has triangles and finite vertices.
void require_writable_mesh(const Mesh& mesh, const std::string& what) {
  if (mesh.triangles.rows() == 0 || mesh.vertices.rows() == 0)
    throw Error(what + " is empty: no surface was found (check the input and options)");
  if (!mesh.vertices.allFinite())
    throw Error(what + " has non-finite vertices (the input's scale is out of range)");
}

// A positive number, or one of `words` (returned as the word's value).
double parse_number_or(const std::string& option, const std::string& text,
                       const std::vector<std::pair<std::string, double>>& words) {
  for (const auto& [word, value] : words)
    if (text == word) return value;
  const std::optional<double> x = parse_finite(text);
  std::string known;
  for (const auto& w : words) known += " or '" + w.first + "'";
  if (!x || !(*x > 0)) throw Error(option + ": '" + text + "' is not a positive number" + known);
  return *x;
}

// --threads: 0 for every core, else at most that many workers while the result lives.
std::unique_ptr<tbb::global_control> limit_threads(int threads) {
  require_range("--threads", threads, 0, 4096);
  if (threads == 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               std::size_t(threads));
}

BandOptions parse_band_options(const std::string& band, const std::string& truncation) {
  BandOptions b;
  b.band = parse_number_or("--band", band, {{"all", std::numeric_limits<double>::infinity()}});
  if (truncation == "auto") {
    b.truncation_mode = TruncationMode::Auto;
  } else if (truncation == "none") {
    b.truncation_mode = TruncationMode::None;
  } else {
    b.truncation_mode = TruncationMode::Given;
    b.truncation = parse_number_or("--truncation (T, auto or none)", truncation, {});
  }
  return b;
}

// A progress bar on stderr for long stages: "[sdfcontour] bricks [=====     ] 12/24, ETA 8 s".
// On a terminal it redraws one line; otherwise it prints a line per tenth.
class ProgressBar {
 public:
  void operator()(const std::string& stage, long done, long total) {
    const auto now = std::chrono::steady_clock::now();
    if (stage != stage_) stage_ = stage, start_ = now, last_tenth_ = -1;
    const double fraction = total > 0 ? double(done) / double(total) : 1.0;
    const int tenth = int(fraction * 10);
    if (!tty_ && tenth == last_tenth_ && done != total) return;
    last_tenth_ = tenth;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const int width = 24, filled = int(fraction * width);
    std::ostringstream line;
    line << "[sdfcontour] " << stage << " [" << std::string(std::size_t(filled), '=')
         << std::string(std::size_t(width - filled), ' ') << "] " << done << "/" << total;
    if (done > 0 && done < total)
      line << ", ETA " << std::fixed << std::setprecision(0) << elapsed * (1 - fraction) / fraction
           << " s";
    std::cerr << (tty_ ? "\r" : "") << line.str() << (tty_ && done < total ? "" : "\n")
              << std::flush;
  }

 private:
  bool tty_ = ::isatty(2);
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
  int last_tenth_ = -1;
};

struct LoadedInput {
  SdfInput input;
  std::unique_ptr<AnalyticShape> shape;  // for built-in shapes
  double vdb_background = 0;             // for OpenVDB level sets: the truncation distance
};

LoadedInput load_input(const std::string& spec, const Bounds& bounds, std::uint64_t seed,
                       const std::string& grid_name) {
  LoadedInput loaded;
  if (is_builtin_spec(spec)) {
    const BuiltinSpec b = parse_builtin_spec(spec);
    loaded.shape = make_builtin_shape(b.name);
    if (b.random) {
      loaded.input.samples = sample_random(*loaded.shape, b.count, bounds, seed);
    } else {
      loaded.input = SdfInput::from_grid(sample_grid(*loaded.shape, b.resolution, bounds));
    }
    return loaded;
  }
  if (is_vdb_path(spec)) {
    VdbLevelSet level_set = read_vdb_level_set(spec, grid_name);
    loaded.input.samples = std::move(level_set.samples);
    loaded.input.spacing = level_set.voxel_size;
    loaded.vdb_background = level_set.background;
    return loaded;
  }
  loaded.input = sdf_input_from_npy(map_npy(spec), bounds);
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
  std::string depth = "8";  // "auto" (contour only): from the grid's resolution

  void add_to(CLI::App* app) {
    app->add_option("--alpha", options.point_weight,
                    "Screening weight (PoissonRecon's --pointWeight); 0 is plain Poisson")
        ->capture_default_str();
    app->add_option("--depth", depth,
                    depth == "auto"
                        ? "Finest octree depth, or 'auto': 8 up to 128 samples per axis, 9 above "
                          "(deeper needs more memory than a 512^3 run should take)"
                        : "Finest octree depth")
        ->capture_default_str();
    app->add_option("--full-depth", options.full_depth, "The octree is complete down to this depth")
        ->capture_default_str();
    app->add_option("--samples-per-node", options.samples_per_node,
                    "Splat each normal where an octree node holds about this many samples")
        ->capture_default_str();
    app->add_option("--scale", options.scale,
                    "Domain = bounding cube of the points enlarged by this factor")
        ->capture_default_str();
    app->add_option("--boundary", boundary,
                    "Boundary condition on the domain cube: neumann, dirichlet (chi = 0 on the "
                    "faces) or free (for these degree-1 elements the same as neumann)")
        ->capture_default_str();
    app->add_option("--solver-tolerance", options.solver_tolerance,
                    "Conjugate gradients stop at this relative residual at each depth")
        ->capture_default_str();
  }
  PoissonOptions resolved() const {
    PoissonOptions o = options;
    require_range("--alpha", o.point_weight, 0, 1e4);
    if (depth == "auto") {
      o.depth = 0;  // the pipeline chooses
      require_range("--full-depth", o.full_depth, 0, 8);
    } else {
      o.depth = int(parse_number_or("--depth", depth, {}));
      require_range("--depth", o.depth, 1, 16);
      if (std::to_string(o.depth) != depth) throw Error("--depth must be a whole number or 'auto'");
      require_range("--full-depth", o.full_depth, 0, o.depth);
    }
    require_range("--samples-per-node", o.samples_per_node, 0.01, 1e6);
    require_range("--scale", o.scale, 1, 16);
    require_range("--solver-tolerance", o.solver_tolerance, 1e-16, 0.5);
    if (boundary == "neumann")
      o.boundary = PoissonBoundary::Neumann;
    else if (boundary == "dirichlet")
      o.boundary = PoissonBoundary::Dirichlet;
    else if (boundary == "free")
      o.boundary = PoissonBoundary::Free;
    else
      throw Error("unknown --boundary '" + boundary + "' (known: neumann, dirichlet, free)");
    return o;
  }
};

PoissonArgs contour_poisson_args() {
  PoissonArgs p;
  p.depth = "auto";
  return p;
}

struct ContourArgs {
  std::string input, output, points, method = "gcp", bounds = "-1,1", stats, gradient = "regular",
                                     weights = "james", band = "4", truncation = "auto", grid;
  int knn = 18, threads = 0, brick_size = BrickOptions{}.size;
  double brick_halo = BrickOptions{}.halo, margin = BandOptions{}.margin;
  double james_epsilon = GradientOptions{}.james_epsilon,
         tie_tolerance = ContactPointOptions{}.tie_tolerance;
  bool fn = false, quiet = false, ascii = false, serial_triangulation = false;
  std::uint64_t seed = 0;
  PoissonArgs poisson = contour_poisson_args();
};

int run_contour(const ContourArgs& a) {
  if (a.output.empty() && a.points.empty())
    throw Error("nothing to write: give -o OUT and/or --points FILE");
  for (const std::string* path : {&a.output, &a.points, &a.stats})
    if (!path->empty()) require_writable(*path);
  OutputBatch outputs;  // every file appears at the end, or none
  const auto threads = limit_threads(a.threads);
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
  require_range("--knn", a.knn, 3, 1000);
  require_range("--james-epsilon", a.james_epsilon, 0, 1e6);
  require_range("--tie-tolerance", a.tie_tolerance, 0, 1);
  opt.knn = a.knn;
  opt.gradient.james_epsilon = a.james_epsilon;
  opt.contact.tie_tolerance = a.tie_tolerance;
  opt.contact.try_tet_gradients = a.fn;
  opt.parallel = !a.serial_triangulation;
  opt.poisson = a.poisson.resolved();
  opt.band = parse_band_options(a.band, a.truncation);
  if (a.brick_size < 0) throw Error("--brick-size must be at least 1 (or 0 for no bricks)");
  opt.bricks.size = a.brick_size;
  if (!(a.brick_halo >= 0) || !std::isfinite(a.brick_halo))
    throw Error("--brick-halo must be a non-negative number of spacings (0: automatic)");
  opt.bricks.halo = a.brick_halo;
  opt.band.margin = a.margin;
  opt.progress = say;
  if (!a.quiet) opt.progress_fraction = ProgressBar();

  const auto t0 = std::chrono::steady_clock::now();
  say("reading " + a.input);
  LoadedInput in = load_input(a.input, parse_bounds(a.bounds), a.seed, a.grid);
  // A level set's background is its truncation distance, unless one is given.
  if (in.vdb_background > 0 && opt.band.truncation_mode == TruncationMode::Auto) {
    opt.band.truncation_mode = TruncationMode::Given;
    opt.band.truncation = in.vdb_background;
  }
  const double load_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ContourResult r = contour(in.input, in.shape.get(), opt);
  r.stages.insert(r.stages.begin(), {"input", load_seconds});

  const auto tw = std::chrono::steady_clock::now();
  const PlyFormat format = a.ascii ? PlyFormat::Ascii : PlyFormat::Binary;
  if (r.mesh) {
    require_writable_mesh(*r.mesh, "the " + a.method + " mesh");
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
  if (r.band_samples > 0) {
    nlohmann::json band = {{"band", a.band},
                           {"spacing", r.band_spacing},
                           {"samples", r.band_samples},
                           {"truncation_detected", r.truncation.detected()}};
    if (r.truncation.inside < std::numeric_limits<double>::infinity())
      band["truncation_inside"] = r.truncation.inside;
    if (r.truncation.outside < std::numeric_limits<double>::infinity())
      band["truncation_outside"] = r.truncation.outside;
    j["band"] = band;
  }
  if (r.bricks)
    j["bricks"] = {{"size", a.brick_size},
                   {"count", r.bricks->bricks},
                   {"retries", r.bricks->retries},
                   {"samples_triangulated", r.bricks->triangulated},
                   {"largest_brick_samples", r.bricks->largest_brick}};
  if (r.hidden >= 0) j["hidden_samples"] = r.hidden;
  if (r.poisson_depth > 0) j["poisson_depth"] = r.poisson_depth;
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
  if (!r.poisson_stages.empty()) {
    nlohmann::json poisson_json = nlohmann::json::object();
    for (const auto& s : r.poisson_stages) poisson_json[s.name] = s.seconds;
    j["poisson_seconds"] = poisson_json;
  }
  j["seconds_total"] = total;
  if (!a.stats.empty()) {
    AtomicFile f(a.stats);
    f.stream() << j.dump(2) << "\n";
    f.commit();
  }
  outputs.commit();

  // The short human summary.
  std::cout << "samples " << r.samples;
  if (r.band_samples > 0) std::cout << ", in band " << r.band_samples;
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
  for (const std::string* path : {&a.output, &a.stats, &a.densities})
    if (!path->empty()) require_writable(*path);
  OutputBatch outputs;
  const auto threads = limit_threads(a.threads);
  PoissonOptions o = a.poisson.resolved();
  if (!a.quiet)
    o.progress = [](const std::string& m) { std::cerr << "[sdfcontour] " << m << "\n"; };
  const auto t0 = std::chrono::steady_clock::now();
  const OrientedPoints points = read_oriented_points(a.input);
  const double read_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PoissonResult r = poisson_reconstruct(points, o);
  require_writable_mesh(r.mesh, "the reconstructed mesh");
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
  j["boundary_fallback"] = r.boundary_fallback;
  j["options"] = {{"alpha", o.point_weight},
                  {"depth", o.depth},
                  {"full_depth", o.full_depth},
                  {"samples_per_node", o.samples_per_node},
                  {"scale", o.scale},
                  {"boundary", a.poisson.boundary},
                  {"solver_tolerance", o.solver_tolerance}};
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
  if (!a.stats.empty()) {
    AtomicFile f(a.stats);
    f.stream() << j.dump(2) << "\n";
    f.commit();
  }
  outputs.commit();
  std::cout << "points " << points.points.rows() << ", mesh " << r.mesh.vertices.rows()
            << " vertices / " << r.mesh.triangles.rows() << " triangles, iso-value " << r.iso_value
            << std::endl;
  return 0;
}

// The options every mesh-writing command shares.
void add_run_options(CLI::App* app, std::string& stats, int& threads, bool& ascii, bool& quiet,
                     const std::string& stats_help) {
  app->add_option("--stats", stats, stats_help);
  app->add_option("--threads", threads, "Worker threads (0: all cores)")->capture_default_str();
  app->add_flag("--ascii", ascii, "Write ASCII PLY instead of binary");
  app->add_flag("-q,--quiet", quiet, "No progress messages on stderr");
}

struct SampleArgs {
  std::string mesh, prefix, bounds = "-1,1";
  int resolution = 0;
  std::size_t random = 0;
  std::uint64_t seed = 0;
  double scale = 0.9, truncate = 0, half_width = 3;
  bool quiet = false, float32 = false;
};

// mesh -> normalised mesh, SDF samples (grid or random) and their exact contact points.
int run_sample(const SampleArgs& a) {
  if ((a.resolution > 0) == (a.random > 0))
    throw Error("give exactly one of --res N and --random COUNT");
  if (a.resolution == 1 || a.resolution > 1024) throw Error("--res must be between 2 and 1024");
  require_range("--scale", a.scale, 1e-6, 1e6);
  auto say = [&](const std::string& m) {
    if (!a.quiet) std::cerr << "[sdfcontour] " << m << "\n";
  };
  const Bounds bounds = parse_bounds(a.bounds);
  say("reading " + a.mesh);
  const Mesh mesh = normalize_mesh(read_mesh(a.mesh), a.scale);
  const MeshSdf sdf(mesh);
  Samples samples;
  if (!(a.truncate >= 0) || !std::isfinite(a.truncate))
    throw Error("--truncate must be a non-negative number of spacings");
  if (a.truncate > 0 && a.resolution == 0) throw Error("--truncate needs a grid (--res N)");
  const bool vdb = is_vdb_path(a.prefix);
  if (vdb && a.resolution == 0) throw Error("a .vdb output needs a grid (--res N)");
  if (vdb && !(a.half_width > 0 && std::isfinite(a.half_width)))
    throw Error("--half-width must be a positive number of voxels");
  // x.vdb writes x.vdb, x_mesh.ply and x_gtcp.ply; a prefix writes PREFIX.npy and the rest.
  const std::string stem = vdb ? a.prefix.substr(0, a.prefix.size() - 4) : a.prefix;
  for (const std::string& path :
       {vdb ? a.prefix : stem + ".npy", stem + "_gtcp.ply", stem + "_mesh.ply"})
    require_writable(path);
  OutputBatch outputs;
  // A level set needs values only inside its band: sample truncated, fast.
  const double truncate = vdb && a.truncate == 0 ? a.half_width + 1 : a.truncate;
  if (a.resolution > 0) {
    say("signed distances on a " + std::to_string(a.resolution) + "^3 grid");
    const double h = (bounds.max - bounds.min).maxCoeff() / (a.resolution - 1);
    const Grid grid = truncate > 0 ? sample_grid_truncated(sdf, a.resolution, bounds, truncate * h)
                                   : sample_grid(sdf, a.resolution, bounds);
    const std::size_t n = std::size_t(a.resolution);
    if (is_vdb_path(a.prefix))
      write_vdb_level_set(a.prefix, grid, a.half_width);
    else if (a.float32)
      write_npy_float32(
          a.prefix + ".npy", {n, n, n},
          std::vector<float>(grid.values.data(), grid.values.data() + grid.values.size()));
    else
      write_npy(a.prefix + ".npy", {n, n, n},
                std::vector<double>(grid.values.data(), grid.values.data() + grid.values.size()));
    // A truncated grid's exact contact points: those of the samples inside the truncation.
    BandOptions all;
    all.band = std::numeric_limits<double>::infinity();
    all.margin = 0;
    all.truncation_mode = truncate > 0 ? TruncationMode::Given : TruncationMode::None;
    all.truncation = (vdb ? a.half_width : truncate) * h;
    samples = select_band(grid, all).samples;
  } else {
    say("signed distances at " + std::to_string(a.random) + " random points");
    samples = sample_random(sdf, a.random, bounds, a.seed);
    std::vector<double> rows(a.random * 4);
    for (std::size_t i = 0; i < a.random; ++i) {
      for (int c = 0; c < 3; ++c) rows[4 * i + std::size_t(c)] = samples.points(Eigen::Index(i), c);
      rows[4 * i + 3] = samples.values[Eigen::Index(i)];
    }
    write_npy(a.prefix + ".npy", {a.random, 4}, rows);
  }
  say("exact contact points");
  const ContactPoints gt = exact_contact_points(samples.points, sdf);
  write_oriented_points(stem + "_gtcp.ply", {gt.points, gt.normals});
  write_mesh(stem + "_mesh.ply", mesh);
  outputs.commit();
  std::cout << "samples " << samples.points.rows() << " -> " << (vdb ? a.prefix : stem + ".npy")
            << ", " << stem << "_gtcp.ply, " << stem << "_mesh.ply" << std::endl;
  return 0;
}

struct EvalArgs {
  std::string recon, gt, output;
  std::size_t samples = 200000;
  std::uint64_t seed = 1;
};

void print_json(const nlohmann::json& j, const std::string& output) {
  if (output.empty()) {
    std::cout << j.dump(2) << std::endl;
    return;
  }
  AtomicFile f(output);
  f.stream() << j.dump(2) << "\n";
  f.commit();
}

int run_eval(const EvalArgs& a) {
  if (a.samples == 0 || a.samples > 100000000)
    throw Error("--samples must be between 1 and 100000000");
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
                     {"euler_characteristic", t.euler_characteristic}};
  if (t.closed) j["recon_mesh"]["genus"] = (2 * long(components) - t.euler_characteristic) / 2;
  print_json(j, a.output);
  return 0;
}

int run_eval_points(const EvalArgs& a) {
  const OrientedPoints points = read_oriented_points(a.recon);
  const MeshSdf sdf(read_mesh(a.gt));
  const Eigen::Index n = points.points.rows();
  std::vector<double> value(static_cast<std::size_t>(n)), alignment(static_cast<std::size_t>(n));
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    int t = 0;
    value[std::size_t(i)] = sdf.unsigned_distance(points.points.row(i).transpose(), nullptr, &t);
    alignment[std::size_t(i)] =
        points.normals.row(i).normalized().dot(sdf.triangle_normal(t).transpose());
  });
  auto summary = [](const std::vector<double>& v) {
    return nlohmann::json{{"median", quantile(v, 0.5)},
                          {"mean", mean(v)},
                          {"p95", quantile(v, 0.95)},
                          {"p05", quantile(v, 0.05)}};
  };
  nlohmann::json j;
  j["points"] = a.recon;
  j["gt"] = a.gt;
  j["count"] = n;
  j["abs_value"] = summary(value);
  j["normal_alignment"] = summary(alignment);
  print_json(j, a.output);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sdfcontour: contour samples of a signed distance function into a triangle mesh"};
  app.require_subcommand(1);
  ContourArgs a;
  CLI::App* contour = app.add_subcommand(
      "contour",
      "Contour SDF samples (grid .npy, scattered .npy, OpenVDB level set .vdb or builtin:NAME@N)");
  contour
      ->add_option("input", a.input,
                   "Grid .npy of shape (nx,ny,nz), scattered samples .npy of shape (n,4) with rows "
                   "x,y,z,value, an OpenVDB float level set .vdb (read sparse; its voxel size and "
                   "transform are used), "
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
  contour
      ->add_option("--band", a.band,
                   "Triangulation methods (all but mc) use only samples with |value| <= BAND "
                   "grid spacings (scattered samples: the side of a cube holding one sample); "
                   "'all' keeps every sample, as in the paper")
      ->capture_default_str();
  contour->add_option("--grid", a.grid,
                      "For a .vdb input: the float level set grid to read (default: the first)");
  contour
      ->add_option("--margin", a.margin,
                   "Samples up to this many spacings beyond the band are triangulated but give "
                   "no contact point: they close the band's stars")
      ->capture_default_str();
  contour
      ->add_option("--truncation", a.truncation,
                   "Values clamped at +-T carry no distance and are left out: T, 'none', or "
                   "'auto' (a sign is truncated at its largest |value| when >= 64 samples, and "
                   ">= 1% of that sign's samples, sit there)")
      ->capture_default_str();
  contour
      ->add_option("--brick-size", a.brick_size,
                   "GCP triangulates the band in bricks of this many spacings, each with a halo, "
                   "in parallel; memory follows a brick, the result equals one global "
                   "triangulation's; 0 triangulates the whole band at once (so does --band all)")
      ->capture_default_str();
  contour
      ->add_option("--brick-halo", a.brick_halo,
                   "First halo around a brick, in spacings (doubled where it does not suffice); "
                   "0: twice the largest |value| in the band and its margin")
      ->capture_default_str();
  contour->add_flag(
      "--fn", a.fn,
      "+FN: if the averaged gradient's point is discarded, try each incident tet's gradient");
  contour->add_option("--seed", a.seed, "Seed for builtin:NAME@random:COUNT")
      ->capture_default_str();
  add_run_options(
      contour, a.stats, a.threads, a.ascii, a.quiet,
      "Write a JSON summary (counts, per-stage seconds, contact point errors for built-ins)");
  contour->add_flag("--serial-triangulation", a.serial_triangulation,
                    "Insert points sequentially (same result, slower)");
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
  add_run_options(poisson, pa.stats, pa.threads, pa.ascii, pa.quiet,
                  "Write a JSON summary (counts, per-stage seconds, per-depth solver figures)");
  pa.poisson.add_to(poisson);

  SampleArgs sa;
  CLI::App* sample = app.add_subcommand(
      "sample", "Closed mesh -> normalised mesh, SDF samples and their exact contact points");
  sample->add_option("mesh", sa.mesh, "Closed triangle mesh (OBJ, PLY or OFF)")->required();
  sample
      ->add_option("-o,--output", sa.prefix,
                   "Output prefix: PREFIX.npy (samples), PREFIX_mesh.ply (the normalised "
                   "mesh), PREFIX_gtcp.ply (exact contact points with normals); or X.vdb: an "
                   "OpenVDB level set (with X_mesh.ply and X_gtcp.ply)")
      ->required();
  sample->add_option("--res", sa.resolution, "Sample an N^3 grid over the bounds");
  sample->add_option("--random", sa.random,
                     "Sample COUNT uniform random points in the bounds instead");
  sample->add_option("--seed", sa.seed, "Seed for --random")->capture_default_str();
  sample
      ->add_option("--scale", sa.scale, "The mesh's longest side is scaled to span [-scale, scale]")
      ->capture_default_str();
  sample->add_option("--bounds", sa.bounds, "Sampled box: MIN,MAX or XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX")
      ->capture_default_str();
  sample
      ->add_option("--truncate", sa.truncate,
                   "Truncate the grid's distances at this many spacings (a TSDF, as OpenVDB "
                   "stores level sets); only blocks near the surface are evaluated, so large "
                   "grids sample fast. 0: exact everywhere")
      ->capture_default_str();
  sample->add_flag("--float32", sa.float32, "Write the grid as float32 (default float64)");
  sample->add_option("--half-width", sa.half_width, "A .vdb level set's narrow band, in voxels")
      ->capture_default_str();
  sample->add_flag("-q,--quiet", sa.quiet, "No progress messages on stderr");

  EvalArgs ea;
  CLI::App* eval = app.add_subcommand(
      "eval", "Distances between a reconstruction and the ground truth, as JSON");
  eval->add_option("recon", ea.recon, "Reconstructed mesh")->required();
  eval->add_option("gt", ea.gt, "Ground-truth mesh")->required();
  eval->add_option("--samples", ea.samples, "Area-uniform samples on each mesh")
      ->capture_default_str();
  eval->add_option("--seed", ea.seed, "Seed for the samples")->capture_default_str();
  eval->add_option("-o,--output", ea.output, "Write the JSON here instead of stdout");

  EvalArgs pe;
  CLI::App* eval_points = app.add_subcommand(
      "eval-points", "Contact points against the ground truth: |phi(c)| and n . grad phi");
  eval_points->add_option("points", pe.recon, "Oriented points (PLY x y z nx ny nz)")->required();
  eval_points->add_option("gt", pe.gt, "Ground-truth closed mesh")->required();
  eval_points->add_option("-o,--output", pe.output, "Write the JSON here instead of stdout");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  remove_temporary_files_on_signals();
  try {
    if (contour->parsed()) return run_contour(a);
    if (poisson->parsed()) return run_poisson(pa);
    if (sample->parsed()) return run_sample(sa);
    if (eval->parsed()) return run_eval(ea);
    if (eval_points->parsed()) return run_eval_points(pe);
  } catch (const InternalError& e) {
    std::cerr << "sdfcontour: error: internal error (please report it): " << e.what() << "\n";
    return 2;
  } catch (const Error& e) {
    std::cerr << "sdfcontour: error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "sdfcontour: error: out of memory (try a smaller --band or --brick-size)\n";
    return 1;
  } catch (const std::exception& e) {
    // Not ours: a library below us failed (CGAL's assertions, say); it is a bug of ours not to
    // have refused the input first.
    std::string what = std::string(e.what()).substr(0, 300);
    for (char& c : what)
      if (c == '\n') c = ' ';
    std::cerr << "sdfcontour: error: internal error (please report it): " << what << "\n";
    return 2;
  }
  return 0;
}
