// Internal: a std::vector allocator for large arrays that a parallel loop fills.
#pragma once

#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace sdfcontour::detail {

/// Leaves trivial elements uninitialised on resize, so that a large array is first touched (its
/// pages faulted in and zeroed by the system) by the parallel loop that fills it, not serially.
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <class U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// A vector whose size is set before a parallel loop fills it.
template <class T>
using Unwritten = std::vector<T, UninitialisedAllocator<T>>;

}  // namespace sdfcontour::detail
