// Internal: a std::vector allocator for large arrays that a parallel loop fills.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace sdfcontour::detail {

/// Whether default-initialising a T writes nothing: trivial types, and the structs of Eigen's
/// fixed-size matrices that opt in beside their type (Eigen's constructors write nothing).
template <class T>
struct LeftUnwritten : std::is_trivially_default_constructible<T> {};
template <class S, int R, int C, int O, int MR, int MC>
struct LeftUnwritten<Eigen::Matrix<S, R, C, O, MR, MC>>
    : std::bool_constant<R != Eigen::Dynamic && C != Eigen::Dynamic> {};

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
    // (A type whose default constructor writes, as std::pair's does, would be zeroed serially.)
    static_assert(LeftUnwritten<U>::value,
                  "Unwritten storage needs a type that default-initialisation leaves unwritten");
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
