// uninitialized_allocator.h — an allocator for large buffers that a parallel loop fills.
#pragma once

#include <memory>
#include <utility>

namespace vdb_shell {

/// An allocator whose construct() without a value leaves the element uninitialised: a
/// std::vector<T, UninitializedAllocator<T>> of n elements costs no pass over them. For large
/// buffers of aggregates whose every element a parallel loop writes first, where a plain vector
/// would initialise them all on one thread (page faults included) before the loop.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U*) noexcept {}
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace vdb_shell
