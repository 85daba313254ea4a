// What the subcommands share: number and option parsing with one-line errors, the run options
// (--stats, --threads, --ascii, --quiet), the progress bar, and the screened Poisson options.
#pragma once

#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/reconstruction/poisson.h"
#include "sdfcontour/types.h"

namespace sdfcontour::cli {

/// The whole of `text` as a finite number, or nothing.
std::optional<double> parse_finite(const std::string& text);

/// --bounds: MIN,MAX or XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX.
Bounds parse_bounds(const std::string& text);

/// Throws Error unless value is finite and within [lo, hi].
void require_range(const std::string& option, double value, double lo, double hi);

/// "auto" (nothing), or the whole of `text` as a whole number in [0, max]; else throws Error
/// naming `option` and `meaning` (what the number counts).
std::optional<int> parse_count_or_auto(const std::string& option, const std::string& text, int max,
                                       const std::string& meaning);

/// A positive number, or one of `words` (returned as the word's value).
double parse_number_or(const std::string& option, const std::string& text,
                       const std::vector<std::pair<std::string, double>>& words);

/// A mesh is written only if it has triangles and finite vertices; throws Error otherwise.
void require_writable_mesh(const Mesh& mesh, const std::string& what);

/// --band and --truncation.
BandOptions parse_band_options(const std::string& band, const std::string& truncation);

/// The JSON to `path` (atomically), or to stdout if path is empty.
void write_json(const nlohmann::json& json, const std::string& path);

/// Seconds since `start`.
double seconds_since(std::chrono::steady_clock::time_point start);

/// The options every mesh-writing command shares.
struct RunOptions {
  std::string stats;
  int threads = 0;
  bool ascii = false, quiet = false;

  void add_to(CLI::App* app, const std::string& stats_help);
  /// A stage message on stderr, unless --quiet.
  void say(const std::string& message) const;
  /// --threads: 0 for every core, else at most that many workers while the result lives.
  std::unique_ptr<tbb::global_control> limit_threads() const;
};

/// The names of `options` given on the command line, comma-separated ("" if none).
std::string given_names(const std::vector<const CLI::Option*>& options);

/// Screened Poisson options, shared by `contour` (gcp, gtcp) and `poisson`.
struct PoissonArgs {
  PoissonOptions options;
  std::string boundary = "neumann";
  std::string depth = "8";     ///< "auto" (contour only): from the grid's resolution
  std::string dilation = "2";  ///< likewise
  std::string degree = "1";    ///< "1" or "2" (parsed here, so a bad one gets our one-line error)

  void add_to(CLI::App* app);
  /// The options, range-checked; depth 0 for "auto".
  PoissonOptions resolved() const;
  /// The names of these options given on the command line, comma-separated ("" if none).
  std::string given() const;

 private:
  std::vector<const CLI::Option*> added_;
};

}  // namespace sdfcontour::cli
