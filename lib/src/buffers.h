// Large buffers: blocks in huge pages, and vectors whose new elements start unset, for the
// buffers their owner fills right after, in parallel.
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace ssgi::detail {

// Blocks of `bytes` for large buffers (buffers.cpp): from kLargeBlock bytes up, aligned to 2 MB
// and, on Linux, advised to be backed by transparent huge pages, which their first touch then
// faults in 2 MB at a time instead of 4 KB (a 1080p plane is 8 MB: 4 faults, not 2025).
// Smaller ones are plain operator new.
void* allocate_block(std::size_t bytes);
void free_block(void* p, std::size_t bytes) noexcept;

// std::allocator, but a new element is default-initialised (a float is left as it is) rather
// than zeroed: for buffers their owner fills right after, in parallel; and large buffers are
// allocated in huge pages (allocate_block).
template <typename T>
struct UninitializedAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <typename U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(allocate_block(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { free_block(p, n * sizeof(T)); }
  template <typename U>
  void construct(U* p) noexcept(noexcept(::new (static_cast<void*>(p)) U)) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// A vector whose resize leaves new elements uninitialised.
template <typename T>
using UninitializedVector = std::vector<T, UninitializedAllocator<T>>;

}  // namespace ssgi::detail
