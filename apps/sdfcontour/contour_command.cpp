// sdfcontour contour: SDF samples (a grid, scattered samples, a .vdb level set or a built-in
// shape) -> a mesh and/or contact points, with a JSON summary.
#include <cmath>
#include <iostream>

#include "cli_options.h"
#include "commands.h"
#include "contour_flags.h"
#include "contour_summary.h"
#include "io/atomic_file.h"
#include "io/file_checks.h"
#include "pipeline/progress_bar.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/io/npy.h"
#include "sdfcontour/io/vdb.h"
#include "sdfcontour/pipeline/option_ranges.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::cli {

namespace {

// Whether a .vdb level set is read a box at a time, for marching cubes or GCP's local
// reconstruction (else sparse, as scattered samples).
bool vdb_read_by_boxes(const ContourOptions& opt) {
  const bool local = opt.reconstruction == Reconstruction::Local ||
                     (opt.reconstruction == Reconstruction::Auto &&
                      local_gradients(opt.gradient_source) && std::isfinite(opt.band.band));
  if (opt.method == Method::Mc) return opt.want_mesh && !opt.want_points;
  return opt.method == Method::Gcp && opt.want_mesh && local;
}

LoadedInput load_input(const std::string& spec, const Bounds& bounds, std::uint64_t seed,
                       const std::string& grid_name, bool vdb_by_boxes) {
  LoadedInput loaded;
  if (!grid_name.empty() && !is_vdb_path(spec))
    throw Error("--grid names a float grid of a .vdb input, and '" + spec + "' is not one");
  if (is_builtin_spec(spec)) {
    const BuiltinSpec b = parse_builtin_spec(spec);
    loaded.shape = make_builtin_shape(b.name);
    if (b.random) {
      loaded.input = ScatteredInput{sample_random(*loaded.shape, b.count, bounds, seed), 0.0};
    } else {
      loaded.input = grid_input(sample_grid(*loaded.shape, b.resolution, bounds));
    }
    return loaded;
  }
  if (is_vdb_path(spec) && vdb_by_boxes) {
    VdbLayout layout;
    BlockedGrid grid = vdb_blocked_grid(spec, grid_name, &layout);
    loaded.input =
        BlockedGridInput{std::move(grid), layout.background, vdb_world_from_grid(layout)};
    return loaded;
  }
  if (is_vdb_path(spec)) {
    VdbLevelSet level_set = read_vdb_level_set(spec, grid_name);
    loaded.input = ScatteredInput{std::move(level_set.samples), level_set.voxel_size};
    loaded.vdb_background = level_set.background;
    return loaded;
  }
  loaded.input = sdf_input_from_npy(map_npy(spec), bounds);
  return loaded;
}

// Options that the reconstruction which ran does not read are said, even with --quiet: a user
// would otherwise take them for having had an effect.
void warn_of_options_not_read(const ContourArgs& a, const ContourOptions& opt,
                              const ContourResult& r) {
  if (!r.mesh || (opt.method != Method::Gcp && opt.method != Method::Gtcp)) return;
  if (r.reconstruction == Reconstruction::Local && r.edge_fans) {
    std::vector<std::string> unused;
    if (a.subdivisions != "auto") unused.push_back("--subdivisions");
    if (a.side_passes != "auto") unused.push_back("--side-passes");
    if (a.no_side_repair) unused.push_back("--no-side-repair");
    for (const std::string& name : unused)
      std::cerr << "sdfcontour: warning: " << name
                << " is not used with edge fans (--edge-fans, on by default from " << kEdgeFansFrom
                << " samples per axis): their vertices stay in their cells, edges and faces "
                   "without subdivision or side rounds\n";
  }
  if (r.reconstruction == Reconstruction::Local) {
    const std::string solver = a.poisson.given(), path = given_names(a.poisson_path_options);
    const std::string poisson = solver + (solver.empty() || path.empty() ? "" : ", ") + path;
    if (!poisson.empty())
      std::cerr << "sdfcontour: warning: " << poisson
                << " set the Poisson reconstruction, and this is the local one (the default on "
                   "grids): give --reconstruction poisson for it\n";
  } else if (const std::string local = given_names(a.local_options); !local.empty()) {
    std::cerr << "sdfcontour: warning: " << local
              << " set the local reconstruction, and this is the Poisson one (scattered "
                 "samples and --reconstruction poisson take it): give a grid or a .vdb level "
                 "set and --reconstruction local for it\n";
  }
}

ContourOptions contour_options(const ContourArgs& a) {
  ContourOptions opt;
  opt.method = parse_method(a.method);
  opt.want_mesh = !a.output.empty();
  opt.want_points = !a.points.empty();
  opt.gradient_source = parse_gradient_source(a.gradient);
  opt.gradient.weighting = parse_gradient_weighting(a.weights);
  require_in_range("--knn", a.knn, "--knn");
  require_in_range("--james-epsilon", a.james_epsilon, "--james-epsilon");
  opt.knn = a.knn;
  opt.gradient.james_epsilon = a.james_epsilon;
  if (a.tie_tolerance != "auto") {
    const std::optional<double> tie = parse_finite(a.tie_tolerance);
    if (!tie) throw Error("--tie-tolerance: '" + a.tie_tolerance + "' is not a number or 'auto'");
    require_in_range("--tie-tolerance", *tie, "--tie-tolerance");
    opt.contact.tie_tolerance = *tie;
    opt.lattice_tie_tolerance = opt.contact.tie_tolerance;
  }
  opt.contact.try_tet_gradients = a.fn;
  opt.parallel = !a.serial_triangulation;
  opt.poisson = a.poisson.resolved();
  opt.band = parse_band_options(a.band, a.truncation);
  opt.bricks.size = parse_count_or_auto("--brick-size", a.brick_size, 1000000,
                                        "a whole number of spacings, 0 for no bricks")
                        .value_or(BrickOptions::kAutoSize);
  if (opt.bricks.size != 0 && opt.bricks.size != BrickOptions::kAutoSize)
    require_in_range("--brick-size", opt.bricks.size, "--brick-size");
  require_in_range("--brick-halo", a.brick_halo, "--brick-halo");
  require_in_range("--margin", a.margin, "--margin");
  opt.bricks.halo = a.brick_halo;
  opt.band.margin = a.margin;
  require_range("--sign-band", a.sign_band, 0, 1e6);
  require_range("--sign-margin", a.sign_margin, 0, 4);
  if (a.sign_constraints && a.no_sign_constraints)
    throw Error("--sign-constraints and --no-sign-constraints contradict each other");
  opt.enforce_signs = a.sign_constraints      ? Switch::On
                      : a.no_sign_constraints ? Switch::Off
                                              : Switch::Auto;
  opt.sign_band = a.sign_band;
  require_range("--sign-radius", a.sign_radius, 0, 16);
  opt.sign_radius = a.sign_radius;
  opt.sign_constraints.margin = a.sign_margin;
  require_range("--sign-trigger", a.sign_trigger, 0, 1);
  opt.sign_constraints.trigger = a.sign_trigger;
  if (a.no_carve) opt.carve = Switch::Off;
  if (a.no_side_repair) opt.side_repair = Switch::Off;
  if (const auto rounds =
          parse_count_or_auto("--side-passes", a.side_passes, int(option_range("--side-passes").hi),
                              "a whole number of rounds")) {
    opt.carving.side_passes = *rounds;
    opt.carve_sides = *rounds > 0 ? Switch::On : Switch::Off;
  }
  opt.reconstruction = parse_reconstruction(a.reconstruction);
  opt.subdivisions =
      parse_count_or_auto("--subdivisions", a.subdivisions, int(option_range("--subdivisions").hi),
                          "a whole number of levels")
          .value_or(-1);
  if (a.split_sag != "auto") {
    opt.split_sag = parse_number_or("--split-sag", a.split_sag, {{"off", 0.0}, {"0", 0.0}});
    require_in_range("--split-sag", opt.split_sag, "--split-sag");
  }
  require_in_range("--adaptivity", a.adaptivity, "--adaptivity");
  opt.adaptivity.tolerance = a.adaptivity;
  opt.adaptivity.brick_spacings = parse_count_or_auto("--adaptivity-bricks", a.adaptivity_bricks,
                                                      int(option_range("--adaptivity-bricks").hi),
                                                      "a whole number of spacings, 0 for one brick")
                                      .value_or(AdaptivityOptions::kAutoBricks);
  require_in_range("--adaptivity-fit", a.adaptivity_fit, "--adaptivity-fit");
  opt.adaptivity.fit_rounds = a.adaptivity_fit;
  require_range("--local-reach", a.local.reach, 0, 1);
  require_range("--local-feature-ratio", a.local.feature_ratio, 0, 1);
  require_range("--local-min-points", a.local.min_points, 1, 1000);
  require_range("--local-depth-scale", a.local.depth_scale, 0, 1e6);
  require_range("--local-max-field-miss", a.local.max_field_miss, 0, 1e6);
  opt.local = a.local;
  opt.local.robust_rounds =
      parse_count_or_auto("--local-robust-rounds", a.local_robust_rounds,
                          int(option_range("--local-robust-rounds").hi), "a whole number of rounds")
          .value_or(kAutoRobustRounds);
  opt.edge_fans = parse_switch("--edge-fans", a.edge_fans);
  opt.project = parse_switch("--projection", a.projection);
  opt.zero_set = parse_switch("--zero-set", a.zero_set);
  opt.thin_parts = parse_switch("--thin-parts", a.thin_parts);
  require_range("--zero-set-mismatch", a.zero_set_mismatch, 0, 1e6);
  opt.zero_set_options.mismatch = a.zero_set_mismatch;
  for (const ProjectionOption& p : kProjectionOptions)
    require_range(p.name, a.projection_options.*p.field, p.lo, p.hi);
  opt.projection = a.projection_options;
  return opt;
}

int run_contour(const ContourArgs& a) {
  if (a.output.empty() && a.points.empty())
    throw Error("nothing to write: give -o OUT and/or --points FILE");
  require_distinct_files({a.input}, {a.output, a.points, a.run.stats});
  for (const std::string* path : {&a.output, &a.points, &a.run.stats})
    if (!path->empty()) require_writable(*path);
  OutputBatch outputs;  // every file appears at the end, or none
  const auto threads = a.run.limit_threads();
  ContourOptions opt = contour_options(a);
  opt.progress = [&](const std::string& m) { a.run.say(m); };
  if (!a.run.quiet) opt.progress_fraction = detail::ProgressBar();

  const auto t0 = std::chrono::steady_clock::now();
  a.run.say("reading " + a.input);
  LoadedInput in =
      load_input(a.input, parse_bounds(a.bounds), a.seed, a.grid, vdb_read_by_boxes(opt));
  // A level set's background is its truncation distance, unless one is given.
  if (in.vdb_background > 0 && opt.band.truncation_mode == TruncationMode::Auto) {
    opt.band.truncation_mode = TruncationMode::Given;
    opt.band.truncation = in.vdb_background;
  }
  const double load_seconds = seconds_since(t0);
  ContourResult r =
      in.shape ? contour_with_exact_sdf(in.input, *in.shape, opt) : contour(in.input, opt);
  // Every decision that changes what the user gets is said, even with --quiet.
  if (!r.fallback.empty())
    std::cerr << "sdfcontour: warning: GCP returned marching cubes' mesh: " << r.fallback << "\n";
  if (r.value_scale != 1)
    std::cerr << "sdfcontour: warning: the values were rescaled by " << r.value_scale
              << " to distances (they change by " << 1 / r.value_scale
              << " per unit length near the surface)\n";
  warn_of_options_not_read(a, opt, r);
  if (r.isolated_samples > 0)
    std::cerr << "sdfcontour: warning: dropped " << r.isolated_samples
              << " isolated samples (fewer than 3 others within " << kIsolationReach
              << " spacings): strays far from the rest cannot place the surface\n";
  r.stages.insert(r.stages.begin(), {"input", load_seconds});

  const auto tw = std::chrono::steady_clock::now();
  const PlyFormat format = a.run.ascii ? PlyFormat::Ascii : PlyFormat::Binary;
  if (r.mesh) {
    require_writable_mesh(*r.mesh, "the " + a.method + " mesh");
    a.run.say("writing " + a.output);
    write_mesh(a.output, *r.mesh, format);
  }
  if (r.contact_points && !a.points.empty()) {
    a.run.say("writing " + a.points);
    write_oriented_points(a.points, {r.contact_points->points, r.contact_points->normals, {}},
                          format);
  }
  r.stages.push_back({"output", seconds_since(tw)});
  const nlohmann::json summary = contour_summary_json(a, opt, in, r);
  if (!a.run.stats.empty()) write_json(summary, a.run.stats);
  outputs.commit();
  print_contour_summary(r, summary["seconds_total"].get<double>());
  return 0;
}

}  // namespace

bool show_all_options = false;

Command add_contour_command(CLI::App& app) {
  auto a = std::make_shared<ContourArgs>();
  CLI::App* c = app.add_subcommand(
      "contour",
      "Contour SDF samples (grid .npy, scattered .npy, OpenVDB level set .vdb or builtin:NAME@N)");
  add_contour_flags(c, *a);
  return {c, [a] { return run_contour(*a); }};
}

}  // namespace sdfcontour::cli
