// Pixel windows and planar float images, the storage every stage works on.
#pragma once

#include <cassert>
#include <cstddef>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace ssgi {

namespace detail {

// Blocks of `bytes` for large buffers (image.cpp): from kLargeBlock bytes up, aligned to 2 MB
// and, on Linux, advised to be backed by transparent huge pages, which their first touch then
// faults in 2 MB at a time instead of 4 KB (a 1080p plane is 8 MB: 4 faults, not 2025).
// Smaller ones are plain operator new.
void* allocate_block(std::size_t bytes);
void free_block(void* p, std::size_t bytes) noexcept;

// std::allocator, but a new element is default-initialised (a float is left as it is) rather
// than zeroed: for buffers their owner fills right after, in parallel (Image's planes); and
// large buffers are allocated in huge pages (allocate_block).
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

}  // namespace detail

// A half-open pixel rectangle [x0, x1) x [y0, y1) in display-window coordinates
// (OpenEXR's windows are inclusive; the reader converts).
struct Box2i {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;

  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  bool contains(const Box2i& o) const {
    return o.x0 >= x0 && o.y0 >= y0 && o.x1 <= x1 && o.y1 <= y1;
  }
  bool operator==(const Box2i& o) const {
    return x0 == o.x0 && y0 == o.y0 && x1 == o.x1 && y1 == o.y1;
  }
  bool operator!=(const Box2i& o) const { return !(*this == o); }
};

// A planar float32 image: `channels` planes of width x height, row-major, no padding.
// An image with zero channels is "absent" (a pass the input does not provide).
class Image {
 public:
  // The planes, one after the other. Growing it (resize) leaves the new values unset.
  using Planes = detail::UninitializedVector<float>;

  Image() = default;
  // Every value `fill`, written in parallel: a frame's planes are tens of megabytes, and one
  // thread writing them (the first touch of their pages) would be a serial part of every frame.
  Image(int width, int height, int channels, float fill = 0.0f);

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  bool empty() const { return channels_ == 0; }
  std::size_t plane_size() const { return static_cast<std::size_t>(width_) * height_; }

  float* plane(int c) {
    assert(c >= 0 && c < channels_);
    return data_.data() + plane_size() * c;
  }
  const float* plane(int c) const {
    assert(c >= 0 && c < channels_);
    return data_.data() + plane_size() * c;
  }
  float& at(int c, int x, int y) { return plane(c)[static_cast<std::size_t>(y) * width_ + x]; }
  float at(int c, int x, int y) const { return plane(c)[static_cast<std::size_t>(y) * width_ + x]; }

  Planes& data() { return data_; }
  const Planes& data() const { return data_; }
  std::size_t bytes() const { return data_.size() * sizeof(float); }

 private:
  int width_ = 0, height_ = 0, channels_ = 0;
  Planes data_;
};

}  // namespace ssgi
