// Pixel windows and planar float images, the storage every stage works on.
#pragma once

#include <cassert>
#include <cstddef>
#include <memory>
#include <vector>

namespace ssgi {

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
  // The planes' storage: large blocks in huge pages, and a new value left unset rather than
  // zeroed, since the image fills its planes right after, in parallel.
  struct Allocator : std::allocator<float> {
    template <typename U>
    struct rebind {
      using other = Allocator;  // an image holds floats only
    };
    float* allocate(std::size_t n);
    void deallocate(float* p, std::size_t n) noexcept;
    void construct(float*) noexcept {}
    void construct(float* p, float v) noexcept { *p = v; }
  };

 public:
  // The planes, one after the other. Growing it (resize) leaves the new values unset.
  using Planes = std::vector<float, Allocator>;

  Image() = default;
  // Every value `fill`, written in parallel: one thread first touching a frame's tens of
  // megabytes would be a serial part of every frame.
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
