// sdfcontour: contour signed distance samples into triangle meshes. One file per subcommand
// (contour, poisson, sample, eval); this one parses and turns errors into one-line messages.
#include <iostream>
#include <string>
#include <vector>

#include "commands.h"
#include "heap.h"
#include "io/atomic_file.h"
#include "sdfcontour/types.h"

using namespace sdfcontour;

int main(int argc, char** argv) {
  cli::keep_freed_heap();
  CLI::App app{"sdfcontour: contour samples of a signed distance function into a triangle mesh"};
  // `contour --help-all`: the contour command's help with its tuning options listed.
  std::vector<std::string> args(argv, argv + argc);
  for (std::string& arg : args)
    if (arg == "--help-all") {
      cli::show_all_options = true;
      arg = "--help";
    }
  std::vector<char*> pointers;
  for (std::string& arg : args) pointers.push_back(arg.data());
  app.require_subcommand(1);
  cli::Command eval_points;
  const std::vector<cli::Command> commands = {
      cli::add_contour_command(app), cli::add_poisson_command(app), cli::add_sample_command(app),
      cli::add_eval_commands(app, eval_points)};
  try {
    app.parse(int(pointers.size()), pointers.data());
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line in the project's format, exit 1, as every other bad input gets.
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    std::cerr << "sdfcontour: error: " << what << " (see sdfcontour --help)\n";
    return 1;
  }
  remove_temporary_files_on_signals();
  try {
    int status = 0;
    for (const cli::Command& c : commands)
      if (c.app->parsed()) status = c.run();
    if (eval_points.app->parsed()) status = eval_points.run();
    // What went to standard output (a summary, eval's JSON) must have arrived (not /dev/full).
    if (!std::cout.flush()) throw IoError("cannot write to standard output");
    return status;
  } catch (const InternalError& e) {
    std::cerr << "sdfcontour: error: internal error (please report it): " << e.what() << "\n";
    return 2;
  } catch (const Error& e) {
    std::cerr << "sdfcontour: error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "sdfcontour: error: out of memory (try a smaller --band or --brick-size)\n";
    return 1;
  } catch (const std::exception& e) {
    // Not ours: a library below us failed (CGAL's assertions, say); it is a bug of ours not to
    // have refused the input first.
    std::string what = std::string(e.what()).substr(0, 300);
    for (char& c : what)
      if (c == '\n') c = ' ';
    std::cerr << "sdfcontour: error: internal error (please report it): " << what << "\n";
    return 2;
  }
  return 0;
}
