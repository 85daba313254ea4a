// Internal: the progress bar the command-line tool and the Python module show on stderr.
#pragma once

#include <chrono>
#include <string>

namespace sdfcontour::detail {

/// A progress bar on stderr for long stages: "[sdfcontour] bricks [=====     ] 12/24, ETA 8 s".
/// On a terminal it redraws one line; otherwise it prints a line per tenth.
class ProgressBar {
 public:
  ProgressBar();
  void operator()(const std::string& stage, long done, long total);

 private:
  bool tty_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
  int last_tenth_ = -1;
  long last_done_ = 0;
};

}  // namespace sdfcontour::detail
