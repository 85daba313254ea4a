// Internal to the CLI: sdfcontour contour's arguments and loaded input, and its summary (the
// --stats JSON and the lines on stdout).
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_options.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::cli {

struct ContourArgs {
  std::string input, output, points,
      method = "gcp", bounds = "-1,1", gradient = "auto", weights = "james", band = "auto",
      truncation = "auto", grid, brick_size = "auto", side_passes = "auto", projection = "auto",
      edge_fans = "auto", reconstruction = "auto", subdivisions = "auto", split_sag = "auto",
      zero_set = "auto", thin_parts = "auto", local_robust_rounds = "auto";
  double zero_set_mismatch = ZeroSetRefinementOptions{}.mismatch;
  int knn = 18;
  double brick_halo = BrickOptions{}.halo, margin = BandOptions{}.margin;
  double adaptivity = 0;
  std::string adaptivity_bricks = "auto";
  int adaptivity_fit = AdaptivityOptions{}.fit_rounds;
  double james_epsilon = GradientOptions{}.james_epsilon;
  std::string tie_tolerance = "auto";
  bool fn = false, serial_triangulation = false, no_sign_constraints = false,
       sign_constraints = false, no_carve = false, no_side_repair = false;
  double sign_band = ContourOptions{}.sign_band, sign_radius = ContourOptions{}.sign_radius,
         sign_margin = SignConstraintOptions{}.margin,
         sign_trigger = SignConstraintOptions{}.trigger;
  ContactProjectionOptions projection_options;
  LocalReconstructionOptions local;
  std::uint64_t seed = 0;
  RunOptions run;
  /// The options that only the Poisson path's sign constraints and side repair read, and those
  /// that only the local reconstruction reads (to tell which were given; PoissonArgs keeps the
  /// solver's).
  std::vector<const CLI::Option*> poisson_path_options, local_options;
  PoissonArgs poisson = [] {
    PoissonArgs p;
    p.depth = "auto";
    p.dilation = "auto";
    return p;
  }();
};

struct LoadedInput {
  SdfInput input;
  std::unique_ptr<AnalyticShape> shape;  // for built-in shapes
  double vdb_background = 0;             // for OpenVDB level sets: the truncation distance
};

/// The summary of one run: its input, options' effects, stage statistics and seconds.
nlohmann::json contour_summary_json(const ContourArgs& a, const ContourOptions& opt,
                                    const LoadedInput& in, const ContourResult& r);

/// The run's counts and seconds on stdout (`total`: the summary's seconds_total).
void print_contour_summary(const ContourResult& r, double total);

}  // namespace sdfcontour::cli
