// Internal: runs a third-party reader on untrusted bytes in a child process, so that whatever the
// bytes make it do (crash, exhaust memory, loop) ends as an error here, never as our crash.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace sdfcontour::detail {

struct IsolationLimits {
  std::size_t memory_bytes = 0;  ///< the child's data segment (heap); 0: no limit
  /// The child's CPU time (it dies of SIGXCPU past it); the parent kills it after 4 times this
  /// plus 10 s of wall-clock time whatever it does.
  double seconds = 60;
};

/// Runs `work` in a forked child and returns the bytes it returned. The child's sdfcontour::Error
/// (IoError) is thrown again here with its message; anything else that ends the child (another
/// exception, running out of memory, a signal, the time limit) throws IoError naming `what`
/// ("cannot read 'x.vdb' as OpenVDB") and the cause. `work` must not start threads' work that
/// the child cannot finish alone (it runs without the parent's thread pool).
std::string run_isolated(const std::function<std::string()>& work, const std::string& what,
                         const IsolationLimits& limits);

}  // namespace sdfcontour::detail
