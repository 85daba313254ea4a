#include "sdfcontour/pipeline/option_ranges.h"

#include <cctype>
#include <cerrno>
#include <clocale>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "sdfcontour/types.h"

namespace sdfcontour {

const std::vector<OptionRange>& option_ranges() {
  static const std::vector<OptionRange> ranges = {
      {"--knn", "knn", 3, 1000},
      {"--james-epsilon", "", 0, 1e6},
      {"--tie-tolerance", "tie_tolerance", 0, 1},
      {"--margin", "margin", 0, 64},
      {"--brick-size", "brick_size", 8, 1e6},  // 0 (no bricks) is accepted apart
      {"--brick-halo", "brick_halo", 0, 1e3},
      {"--alpha", "alpha", 0, 1e4},
      {"--depth", "depth", 1, 14},
      {"--full-depth", "full_depth", 1, 8},
      {"--refine-dilation", "refine_dilation", 1, 4},
      {"--samples-per-node", "samples_per_node", 0.01, 1e6},
      {"--scale", "scale", 1, 16},
      {"--solver-tolerance", "solver_tolerance", 1e-16, 0.5},
      {"--finest-solver-tolerance", "finest_solver_tolerance", 1e-16, 0.5},
      {"--subdivisions", "subdivisions", 0, 4},
      {"--split-sag", "split_sag", 0, 1},
      {"--adaptivity", "adaptivity", 0, 10},
      {"--adaptivity-bricks", "", 0, 4096},
      {"--adaptivity-fit", "", 0, 100},
      {"--side-passes", "side_passes", 0, 100},
      {"--local-robust-rounds", "", 0, 100},
      {"--res", "resolution", 2, 1024},
      {"--random", "", 1, 1e8},  // sample's random points: 3.2 GB of rows at the top
      {"--threads", "", 0, 4096},
  };
  return ranges;
}

const std::vector<OptionName>& contour_option_names() {
  // (--no-sign-constraints is the CLI's second spelling of sign_constraints=False.)
  static const std::vector<OptionName> names = {
      {"help", "", true},
      {"help-all", "", true},
      {"output", "", true},
      {"points", "", true},
      {"method", "method", true},
      {"bounds", "bounds", true},
      {"band", "band", true},
      {"reconstruction", "reconstruction", true},
      {"adaptivity", "adaptivity", true},
      {"grid", "grid_name", true},
      {"truncation", "truncation", true},
      {"seed", "", true},
      {"stats", "return_stats", true},
      {"threads", "", true},
      {"ascii", "", true},
      {"quiet", "progress", true},
      {"gradient", "gradient", false},
      {"weights", "weights", false},
      {"knn", "knn", false},
      {"james-epsilon", "", false},
      {"tie-tolerance", "tie_tolerance", false},
      {"sign-constraints", "sign_constraints", false},
      {"no-sign-constraints", "", false},
      {"no-carve", "carve", false},
      {"no-side-repair", "", false},
      {"side-passes", "side_passes", false},
      {"adaptivity-bricks", "", false},
      {"adaptivity-fit", "", false},
      {"subdivisions", "subdivisions", false},
      {"split-sag", "split_sag", false},
      {"thin-parts", "thin_parts", false},
      {"edge-fans", "edge_fans", false},
      {"local-reach", "", false},
      {"local-feature-ratio", "", false},
      {"local-robust-rounds", "", false},
      {"local-min-points", "", false},
      {"local-max-field-miss", "", false},
      {"local-depth-scale", "", false},
      {"zero-set", "zero_set", false},
      {"zero-set-mismatch", "", false},
      {"projection", "projection", false},
      {"projection-radius", "", false},
      {"projection-max-move", "", false},
      {"projection-agreement", "", false},
      {"projection-depth-scale", "", false},
      {"projection-variance", "", false},
      {"projection-residual", "", false},
      {"sign-band", "", false},
      {"sign-radius", "", false},
      {"sign-margin", "", false},
      {"sign-trigger", "", false},
      {"margin", "margin", false},
      {"brick-size", "brick_size", false},
      {"brick-halo", "brick_halo", false},
      {"fn", "fn", false},
      {"serial-triangulation", "", false},
      {"alpha", "alpha", false},
      {"depth", "depth", false},
      {"degree", "degree", false},
      {"full-depth", "full_depth", false},
      {"refine-dilation", "refine_dilation", false},
      {"samples-per-node", "samples_per_node", false},
      {"scale", "scale", false},
      {"boundary", "boundary", false},
      {"solver-tolerance", "solver_tolerance", false},
      {"finest-solver-tolerance", "finest_solver_tolerance", false},
      {"", "sdf", true},
      {"", "resolution", true},
      {"", "level", true},
      {"", "spacing", true},
      {"", "origin", true},
      {"", "return_normals", true},
      {"", "lipschitz", false},
      {"", "batch_size", false},
      {"", "refine", false},
      {"", "strict", false},
  };
  return names;
}

const OptionRange& option_range(const std::string& cli_name) {
  for (const OptionRange& r : option_ranges())
    if (cli_name == r.cli) return r;
  throw InternalError("no range for option " + cli_name);
}

void require_in_range(const std::string& cli_name, double value, const std::string& name) {
  const OptionRange& r = option_range(cli_name);
  if (!std::isfinite(value) || value < r.lo || value > r.hi) {
    std::ostringstream m;
    m << name << " must be a finite number between " << r.lo << " and " << r.hi << ", got "
      << value;
    throw Error(m.str());
  }
}

std::optional<double> parse_number(const std::string& text) {
  // (strtod skips leading blanks, which Python's float() also strips: refused here for both.)
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return std::nullopt;
  const locale_t c = newlocale(LC_NUMERIC_MASK, "C", locale_t(0));
  char* end = nullptr;
  errno = 0;
  const double x = c ? strtod_l(text.c_str(), &end, c) : std::strtod(text.c_str(), &end);
  if (c) freelocale(c);
  // (ERANGE with a finite result is an underflow to a subnormal or zero: a number still.)
  if (end != text.c_str() + text.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

}  // namespace sdfcontour
