#include "pipeline/progress_bar.h"

#include <unistd.h>

#include <iomanip>
#include <iostream>
#include <sstream>

namespace sdfcontour::detail {

ProgressBar::ProgressBar() : tty_(::isatty(2)) {}

void ProgressBar::operator()(const std::string& stage, long done, long total) {
  const auto now = std::chrono::steady_clock::now();
  // A new stage, or the same one started again (one Poisson solve per far-apart object).
  if (stage != stage_ || done < last_done_) stage_ = stage, start_ = now, last_tenth_ = -1;
  last_done_ = done;
  const double fraction = total > 0 ? double(done) / double(total) : 1.0;
  const int tenth = int(fraction * 10);
  if (!tty_ && tenth == last_tenth_ && done != total) return;
  last_tenth_ = tenth;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const int width = 24, filled = int(fraction * width);
  std::ostringstream line;
  line << "[sdfcontour] " << stage << " [" << std::string(std::size_t(filled), '=')
       << std::string(std::size_t(width - filled), ' ') << "] " << done << "/" << total;
  if (done > 0 && done < total)
    line << ", ETA " << std::fixed << std::setprecision(0) << elapsed * (1 - fraction) / fraction
         << " s";
  std::cerr << (tty_ ? "\r" : "") << line.str() << (tty_ && done < total ? "" : "\n") << std::flush;
}

}  // namespace sdfcontour::detail
