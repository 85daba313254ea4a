// libFuzzer target: arbitrary text as an option's value, read the one way every entry point
// reads a number (parse_number) and checked against every option's range. Findings: a crash, a
// sanitizer report, an exception other than sdfcontour::Error, an error message of more than one
// line, a number accepted that is not the whole text, or one that does not read back the same.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <string>

#include "sdfcontour/pipeline/option_ranges.h"
#include "sdfcontour/types.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::optional<double> x = sdfcontour::parse_number(text);
  if (!x) return 0;
  if (!std::isfinite(*x) || text.find('\0') != std::string::npos) std::abort();
  // Written the shortest way and read again: the same double.
  char shortest[64];
  const auto [end, error] = std::to_chars(shortest, shortest + sizeof shortest, *x);
  if (error != std::errc()) std::abort();
  const std::optional<double> again = sdfcontour::parse_number(std::string(shortest, end));
  if (!again || *again != *x) std::abort();
  for (const sdfcontour::OptionRange& range : sdfcontour::option_ranges()) {
    try {
      sdfcontour::require_in_range(range.cli, *x, range.cli);
      if (!(*x >= range.lo && *x <= range.hi)) std::abort();  // accepted out of its range
    } catch (const sdfcontour::Error& e) {
      if (std::string(e.what()).find('\n') != std::string::npos) std::abort();
      if (*x >= range.lo && *x <= range.hi) std::abort();  // refused inside its range
    }
  }
  return 0;
}
