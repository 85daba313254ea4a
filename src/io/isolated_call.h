// Internal: runs a third-party reader on untrusted bytes in a child process, so that whatever the
// bytes make it do (crash, exhaust memory, loop) ends as an error here, never as our crash.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace sdfcontour::detail {

struct IsolationLimits {
  std::size_t memory_bytes = 0;  ///< the child's data segment (heap); 0: no limit
  double seconds = 60;           ///< the child is killed after this long
};

/// Runs `work` in a forked child and returns the bytes it returned. The child's sdfcontour::Error
/// (IoError) is thrown again here with its message; anything else that ends the child (another
/// exception, running out of memory, a signal, the time limit) throws IoError naming `what`
/// ("cannot read 'x.vdb' as OpenVDB") and the cause. `work` must not start threads' work that
/// the child cannot finish alone (it runs without the parent's thread pool).
std::string run_isolated(const std::function<std::string()>& work, const std::string& what,
                         const IsolationLimits& limits);

}  // namespace sdfcontour::detail
