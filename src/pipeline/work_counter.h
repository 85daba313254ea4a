// Internal: a parallel loop's work done, reported as a fraction.
#pragma once

#include <algorithm>
#include <atomic>
#include <functional>
#include <mutex>

namespace sdfcontour::detail {

/// Counts the items a parallel loop has taken and reports (done, total) to `report` about every
/// 1%, one call at a time and rising, so a callback that is not thread-safe (the CLI's bar) may
/// be given. An empty `report` costs one branch per item.
class WorkCounter {
 public:
  WorkCounter(const std::function<void(long, long)>& report, long total)
      : report_(report), total_(total), step_(std::max(1L, total / 100)) {}

  void add(long items = 1) {
    if (!report_ || items <= 0) return;
    const long done = done_.fetch_add(items) + items;
    if (done / step_ == (done - items) / step_ && done < total_) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    if (done <= reported_) return;
    reported_ = done;
    report_(std::min(done, total_), total_);
  }

 private:
  const std::function<void(long, long)>& report_;
  const long total_, step_;
  std::atomic<long> done_{0};
  std::mutex mutex_;
  long reported_ = 0;
};

}  // namespace sdfcontour::detail
