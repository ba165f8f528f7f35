#include "ssgi/image.h"

#include <new>

#include "buffers.h"
#include "parallel.h"

namespace ssgi {

float* Image::Allocator::allocate(std::size_t n) {
  if (n > static_cast<std::size_t>(-1) / sizeof(float)) throw std::bad_array_new_length();
  return static_cast<float*>(detail::allocate_block(n * sizeof(float)));
}

void Image::Allocator::deallocate(float* p, std::size_t n) noexcept {
  detail::free_block(p, n * sizeof(float));
}

Image::Image(int width, int height, int channels, float fill)
    : width_(width),
      height_(height),
      channels_(channels),
      data_(static_cast<std::size_t>(width) * height * channels) {
  detail::parallel_fill(data_.data(), data_.size(), fill);
}

}  // namespace ssgi
