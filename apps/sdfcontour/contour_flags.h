// The contour command's options (contour_flags.cpp): each one's name, help and group.
#pragma once

#include <CLI/CLI.hpp>
#include <array>

#include "contour_summary.h"
#include "sdfcontour/reconstruction/contact_projection.h"

namespace sdfcontour::cli {

// The projection's numeric options: name, field, allowed range, help.
struct ProjectionOption {
  const char* name;
  double ContactProjectionOptions::*field;
  double lo, hi;
  const char* help;
};
extern const std::array<ProjectionOption, 6> kProjectionOptions;

// Declares every option of `contour` on c, with a's fields as their targets, its help in two
// levels (--help and --help-all) and its formatter.
void add_contour_flags(CLI::App* c, ContourArgs& a);

}  // namespace sdfcontour::cli
