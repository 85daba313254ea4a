#include "cli_options.h"

#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>

#include "io/atomic_file.h"
#include "sdfcontour/pipeline/option_ranges.h"

namespace sdfcontour::cli {

std::optional<double> parse_finite(const std::string& text) {
  return parse_number(text);
}

std::optional<int> parse_count_or_auto(const std::string& option, const std::string& text, int max,
                                       const std::string& meaning) {
  if (text == "auto") return std::nullopt;
  const std::optional<double> x = parse_finite(text);
  if (!x || *x < 0 || *x != std::floor(*x) || *x > max)
    throw Error(option + " must be " + meaning + " (0 to " + std::to_string(max) +
                ") or 'auto', got '" + text + "'");
  return int(*x);
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

void require_range(const std::string& option, double value, double lo, double hi) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    std::ostringstream m;
    m << option << " must be a finite number between " << lo << " and " << hi << ", got " << value;
    throw Error(m.str());
  }
}

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

void require_writable_mesh(const Mesh& mesh, const std::string& what) {
  if (mesh.triangles.rows() == 0 || mesh.vertices.rows() == 0)
    throw Error(what + " is empty: no surface was found (check the input and options)");
  if (!mesh.vertices.allFinite())
    throw Error(what + " has non-finite vertices (the input's scale is out of range)");
}

BandOptions parse_band_options(const std::string& band, const std::string& truncation) {
  BandOptions b;
  b.band = parse_number_or("--band", band,
                           {{"all", std::numeric_limits<double>::infinity()}, {"auto", 0.0}});
  if (band != "auto" && !(b.band > 0))
    throw Error("the band must be a positive number of spacings (or 'all' or 'auto'), got " + band);
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

void write_json(const nlohmann::json& json, const std::string& path) {
  if (path.empty()) {
    std::cout << json.dump(2) << std::endl;
    return;
  }
  AtomicFile f(path);
  f.stream() << json.dump(2) << "\n";
  f.commit();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void RunOptions::add_to(CLI::App* app, const std::string& stats_help) {
  app->add_option("--stats", stats, stats_help);
  app->add_option("--threads", threads, "Worker threads (0: all cores)")->capture_default_str();
  app->add_flag("--ascii", ascii, "Write ASCII PLY instead of binary");
  app->add_flag("-q,--quiet", quiet, "No progress messages on stderr");
}

void RunOptions::say(const std::string& message) const {
  if (!quiet) std::cerr << "[sdfcontour] " << message << "\n";
}

std::unique_ptr<tbb::global_control> RunOptions::limit_threads() const {
  require_in_range("--threads", threads, "--threads");
  if (threads == 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               std::size_t(threads));
}

void PoissonArgs::add_to(CLI::App* app) {
  added_.push_back(
      app->add_option("--alpha", options.point_weight,
                      "Screening weight (PoissonRecon's --pointWeight); 0 is plain Poisson")
          ->capture_default_str());
  added_.push_back(
      app->add_option("--depth", depth,
                      depth == "auto"
                          ? "Finest octree depth, or 'auto': 8 up to 128 samples per axis, 9 up to "
                            "256, 10 up to 512, 11 above (in all: a 512^3 grid 1.4-2.2 GB, "
                            "1024^3 6.1-8.4 GB)"
                          : "Finest octree depth")
          ->capture_default_str());
  added_.push_back(
      app->add_option(
             "--degree", degree,
             "Poisson elements: 1, trilinear; 2, quadratic B-splines (PoissonRecon's default; "
             "smoother, slower)")
          ->capture_default_str());
  added_.push_back(app->add_option("--full-depth", options.full_depth,
                                   "The octree is complete down to this depth")
                       ->capture_default_str());
  added_.push_back(
      app->add_option(
             "--refine-dilation", dilation,
             std::string("Each depth refines the cells within this many cells of the points' "
                         "(1-4; 1 is cheaper, less accurate where points are sparse)") +
                 (dilation == "auto" ? "; 'auto': 2 below 256 samples per axis, 1 from 256" : ""))
          ->capture_default_str());
  added_.push_back(
      app->add_option("--samples-per-node", options.samples_per_node,
                      "Splat each normal where an octree node holds about this many samples")
          ->capture_default_str());
  added_.push_back(app->add_option("--scale", options.scale,
                                   "Domain = bounding cube of the points enlarged by this factor")
                       ->capture_default_str());
  added_.push_back(
      app->add_option(
             "--boundary", boundary,
             "Boundary condition on the domain cube: neumann, dirichlet (chi = 0 on the "
             "faces) or free (B-splines reaching in from outside kept as they are; for degree 1 "
             "the same as neumann)")
          ->capture_default_str());
  added_.push_back(
      app->add_option(
             "--solver-tolerance", options.solver_tolerance,
             "Conjugate gradients stop at this relative residual at each depth but the finest")
          ->capture_default_str());
  added_.push_back(
      app->add_option("--finest-solver-tolerance", options.finest_solver_tolerance,
                      "... and at this one at the finest depth (most of the solve's time)")
          ->capture_default_str());
}

namespace {

// A whole number in [lo, hi], or 0 for "auto" (the pipeline chooses). The range is checked
// before the conversion to int, which a huge value would make undefined.
int whole_number_or_auto(const std::string& option, const std::string& text, int lo, int hi) {
  if (text == "auto") return 0;
  const double value = parse_number_or(option, text, {});
  require_range(option, value, lo, hi);
  const int whole = int(value);
  if (std::to_string(whole) != text) throw Error(option + " must be a whole number or 'auto'");
  return whole;
}

}  // namespace

std::string given_names(const std::vector<const CLI::Option*>& options) {
  std::string names;
  for (const CLI::Option* o : options)
    if (o->count() > 0) names += (names.empty() ? "" : ", ") + o->get_name();
  return names;
}

std::string PoissonArgs::given() const {
  return given_names(added_);
}

PoissonOptions PoissonArgs::resolved() const {
  PoissonOptions o = options;
  require_in_range("--alpha", o.point_weight, "--alpha");
  o.depth = whole_number_or_auto("--depth", depth, int(option_range("--depth").lo),
                                 int(option_range("--depth").hi));
  if (degree != "1" && degree != "2") throw Error("--degree must be 1 or 2, got '" + degree + "'");
  o.degree = std::stoi(degree);
  require_in_range("--full-depth", o.full_depth, "--full-depth");
  if (o.depth > 0 && o.full_depth > o.depth) throw Error("--full-depth must be at most --depth");
  o.refine_dilation =
      whole_number_or_auto("--refine-dilation", dilation, int(option_range("--refine-dilation").lo),
                           int(option_range("--refine-dilation").hi));
  require_in_range("--samples-per-node", o.samples_per_node, "--samples-per-node");
  require_in_range("--scale", o.scale, "--scale");
  require_in_range("--solver-tolerance", o.solver_tolerance, "--solver-tolerance");
  require_in_range("--finest-solver-tolerance", o.finest_solver_tolerance,
                   "--finest-solver-tolerance");
  o.boundary = parse_poisson_boundary(boundary);
  return o;
}

}  // namespace sdfcontour::cli
