// sdfcontour sample: a closed mesh -> its normalised copy, SDF samples (a grid, a truncated grid,
// an OpenVDB level set or random points) and their exact contact points.
#include <filesystem>
#include <iostream>
#include <limits>

#include "cli_options.h"
#include "commands.h"
#include "io/atomic_file.h"
#include "io/file_checks.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/input/mesh_union.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/io/npy.h"
#include "sdfcontour/io/vdb.h"
#include "sdfcontour/pipeline/option_ranges.h"

namespace sdfcontour::cli {

namespace {

struct SampleArgs {
  std::string mesh, prefix, bounds = "-1,1";
  int resolution = 0;
  long random = 0;
  std::uint64_t seed = 0;
  double scale = 0.9, truncate = 0, half_width = 3;
  bool quiet = false, float32 = false;
};

void check(const SampleArgs& a, bool vdb) {
  if (a.random != 0) require_in_range("--random", double(a.random), "--random");
  if ((a.resolution > 0) == (a.random > 0))
    throw Error("give exactly one of --res N and --random COUNT");
  if (a.resolution != 0) require_in_range("--res", a.resolution, "--res");
  require_range("--scale", a.scale, 1e-6, 1e6);
  if (!(a.truncate >= 0) || !std::isfinite(a.truncate))
    throw Error("--truncate must be a non-negative number of spacings");
  if (a.truncate > 0 && a.resolution == 0) throw Error("--truncate needs a grid (--res N)");
  if (vdb && a.resolution == 0) throw Error("a .vdb output needs a grid (--res N)");
  if (vdb && !(a.half_width > 0 && std::isfinite(a.half_width)))
    throw Error("--half-width must be a positive number of voxels");
}

// Samples the grid, writes it (.npy or .vdb) and returns the samples that carry a distance.
Samples write_grid(const SampleArgs& a, const std::string& path, const MeshSdf& sdf,
                   const Bounds& bounds, bool vdb) {
  // A level set needs values only inside its band: sample truncated, fast.
  const double truncate = vdb && a.truncate == 0 ? a.half_width + 1 : a.truncate;
  const double h = (bounds.max - bounds.min).maxCoeff() / (a.resolution - 1);
  const Grid grid = truncate > 0 ? sample_grid_truncated(sdf, a.resolution, bounds, truncate * h)
                                 : sample_grid(sdf, a.resolution, bounds);
  // A shape thinner than a spacing can fall between the samples.
  if (grid.values.minCoeff() >= 0 || grid.values.maxCoeff() < 0)
    throw Error("no sample of the " + std::to_string(a.resolution) +
                "^3 grid lies inside the mesh (or none outside): it is thinner than a spacing "
                "there; sample with a larger --res");
  const std::size_t n = std::size_t(a.resolution);
  if (vdb)
    write_vdb_level_set(path, grid, a.half_width);
  else  // straight from the grid: no copy of its values (8 GB at 1024^3)
    write_npy(path, {n, n, n}, grid.values.data(), std::size_t(grid.values.size()),
              a.float32 ? ScalarType::Float32 : ScalarType::Float64);
  // A truncated grid's exact contact points: those of the samples inside the truncation.
  BandOptions all;
  all.band = std::numeric_limits<double>::infinity();
  all.margin = 0;
  all.truncation_mode = truncate > 0 ? TruncationMode::Given : TruncationMode::None;
  all.truncation = (vdb ? a.half_width : truncate) * h;
  return select_band(grid, all).samples;
}

Samples write_random(const SampleArgs& a, const std::string& path, const MeshSdf& sdf,
                     const Bounds& bounds) {
  const std::size_t count = std::size_t(a.random);
  Samples samples = sample_random(sdf, count, bounds, a.seed);
  std::vector<double> rows(count * 4);
  for (std::size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) rows[4 * i + std::size_t(c)] = samples.points(Eigen::Index(i), c);
    rows[4 * i + 3] = samples.values[Eigen::Index(i)];
  }
  write_npy(path, {count, 4}, rows);
  return samples;
}

// The mesh as one closed surface: overlapping parts united, what is left said on stderr.
Mesh closed_surface(const Mesh& mesh, const RunOptions& run) {
  require_closed_mesh(mesh, "the mesh");
  MeshUnionStats u;
  Mesh out = union_of_overlapping_parts(mesh, &u);
  if (u.parts_united > 0)
    run.say("united " + std::to_string(u.parts_united + 1) + " overlapping parts into one surface");
  if (u.crossings_left > 0)
    std::cerr << "sdfcontour: warning: the mesh crosses itself (" << u.crossings_left
              << " pairs of triangles): inside is where its winding number is not zero, and "
                 "distances near the crossings are to every triangle\n";
  return out;
}

int run_sample(const SampleArgs& a) {
  const bool vdb = is_vdb_path(a.prefix);
  check(a, vdb);
  RunOptions run;
  run.quiet = a.quiet;
  const Bounds bounds = parse_bounds(a.bounds);
  // x.vdb writes x.vdb, x_mesh.ply and x_gtcp.ply; a prefix (or x.npy) writes PREFIX.npy and
  // the rest.
  const bool npy =
      !vdb && a.prefix.size() > 4 && a.prefix.compare(a.prefix.size() - 4, 4, ".npy") == 0;
  const std::string stem = vdb || npy ? a.prefix.substr(0, a.prefix.size() - 4) : a.prefix;
  const std::string samples_path = vdb ? a.prefix : stem + ".npy";
  const std::string name = std::filesystem::path(stem).filename().string();
  std::error_code ec;
  if (name.empty() || name == "." || name == ".." || std::filesystem::is_directory(stem, ec))
    throw Error("-o '" + a.prefix +
                "' names a folder: give a file name prefix (dir/bunny writes dir/bunny.npy, ...)");
  const std::vector<std::string> paths = {samples_path, stem + "_gtcp.ply", stem + "_mesh.ply"};
  require_distinct_files({a.mesh}, paths);
  for (const std::string& path : paths) require_writable(path);
  OutputBatch outputs;
  run.say("reading " + a.mesh);
  const Mesh mesh = closed_surface(normalize_mesh(read_mesh(a.mesh), a.scale), run);
  const MeshSdf sdf(mesh);
  Samples samples;
  if (a.resolution > 0) {
    run.say("signed distances on a " + std::to_string(a.resolution) + "^3 grid");
    samples = write_grid(a, samples_path, sdf, bounds, vdb);
  } else {
    run.say("signed distances at " + std::to_string(a.random) + " random points");
    samples = write_random(a, samples_path, sdf, bounds);
  }
  run.say("exact contact points");
  const ContactPoints gt = exact_contact_points(samples.points, sdf);
  write_oriented_points(stem + "_gtcp.ply", {gt.points, gt.normals, {}});
  write_mesh(stem + "_mesh.ply", mesh);
  outputs.commit();
  std::cout << "samples " << samples.points.rows() << " -> " << samples_path << ", " << stem
            << "_gtcp.ply, " << stem << "_mesh.ply" << std::endl;
  return 0;
}

}  // namespace

Command add_sample_command(CLI::App& app) {
  auto a = std::make_shared<SampleArgs>();
  CLI::App* c = app.add_subcommand(
      "sample", "Closed mesh -> normalised mesh, SDF samples and their exact contact points");
  c->add_option("mesh", a->mesh, "Closed triangle mesh (OBJ, PLY or OFF)")->required();
  c->add_option(
       "-o,--output", a->prefix,
       "Output prefix (or PREFIX.npy): PREFIX.npy (samples), PREFIX_mesh.ply (the normalised "
       "mesh), PREFIX_gtcp.ply (exact contact points with normals); or X.vdb: an "
       "OpenVDB level set (with X_mesh.ply and X_gtcp.ply)")
      ->required();
  c->add_option("--res", a->resolution, "Sample an N^3 grid over the bounds");
  c->add_option("--random", a->random, "Sample COUNT uniform random points in the bounds instead");
  c->add_option("--seed", a->seed, "Seed for --random")->capture_default_str();
  c->add_option("--scale", a->scale, "The mesh's longest side is scaled to span [-scale, scale]")
      ->capture_default_str();
  c->add_option("--bounds", a->bounds, "Sampled box: MIN,MAX or XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX")
      ->capture_default_str();
  c->add_option("--truncate", a->truncate,
                "Truncate the grid's distances at this many spacings (a TSDF, as OpenVDB "
                "stores level sets); only blocks near the surface are evaluated, so large "
                "grids sample fast. 0: exact everywhere")
      ->capture_default_str();
  c->add_flag("--float32", a->float32, "Write the grid as float32 (default float64)");
  c->add_option("--half-width", a->half_width, "A .vdb level set's narrow band, in voxels")
      ->capture_default_str();
  c->add_flag("-q,--quiet", a->quiet, "No progress messages on stderr");
  return {c, [a] { return run_sample(*a); }};
}

}  // namespace sdfcontour::cli
