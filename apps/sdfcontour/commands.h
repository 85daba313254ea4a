// The subcommands. Each adds itself (its options and help) to the app and returns how to run it.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace sdfcontour::cli {

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;  ///< returns the exit code; throws Error for bad input
};

/// Whether `contour --help-all` was asked for: its tuning options are then listed (else hidden
/// from --help, and still accepted). Set by main before the commands are added.
extern bool show_all_options;

Command add_contour_command(CLI::App& app);                      ///< sdfcontour contour
Command add_poisson_command(CLI::App& app);                      ///< sdfcontour poisson
Command add_sample_command(CLI::App& app);                       ///< sdfcontour sample
Command add_eval_commands(CLI::App& app, Command& eval_points);  ///< eval and eval-points

}  // namespace sdfcontour::cli
