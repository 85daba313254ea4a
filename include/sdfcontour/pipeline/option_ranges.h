// The contour options' one table for the command-line tool and the Python module alike: every
// option's names as both spell it and whether a user decides it (else it is a tuning knob), and
// every numeric option's accepted range, so each entry point says what is wrong in its own words.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace sdfcontour {

/// One numeric option: its CLI name ("--alpha"), its Python keyword ("alpha", empty where Python
/// has none) and the closed range [lo, hi] of accepted values.
struct OptionRange {
  const char* cli;
  const char* python;
  double lo, hi;
};

/// Every numeric option's range. The limits keep a run finite in time and memory (a complete
/// octree of depth 9 already has 134 million cells) and its arithmetic in range.
const std::vector<OptionRange>& option_ranges();

/// A contour option as the CLI and Python spell it. `cli` is the long name without "--" (empty for
/// a Python keyword with no CLI option); `python` the keyword of sdfcontour.contour() (empty for a
/// CLI option with no keyword). `user`: listed by `contour --help` (the rest by --help-all).
struct OptionName {
  const char* cli;
  const char* python;
  bool user;
};

/// Every option of `sdfcontour contour` and every keyword of sdfcontour.contour(). The CLI refuses
/// to start with an option this table lacks (InternalError), and the Python tests check the
/// keywords against it, so a name is added here first.
const std::vector<OptionName>& contour_option_names();

/// The range of the option with this CLI name; throws InternalError if there is none.
const OptionRange& option_range(const std::string& cli_name);

/// Throws Error ("`name` must be a finite number between lo and hi, got value") unless `value`
/// is in the range of the option whose CLI name is `cli_name`; `name` is how the caller spells
/// the option (its CLI name, or its Python keyword).
void require_in_range(const std::string& cli_name, double value, const std::string& name);

/// A number written as text, the one way every entry point reads one: the whole text a decimal or
/// hexadecimal floating-point number in the C locale ("1e-3", "0x1p-4"; a subnormal is kept),
/// finite; nullopt for anything else ("0_1", " 1", "1 ", "nan", "inf", "").
std::optional<double> parse_number(const std::string& text);

}  // namespace sdfcontour
