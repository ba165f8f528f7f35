#include "ssgi/image.h"

#include "parallel.h"

namespace ssgi {

Image::Image(int width, int height, int channels, float fill)
    : width_(width),
      height_(height),
      channels_(channels),
      data_(static_cast<std::size_t>(width) * height * channels) {
  detail::parallel_fill(data_.data(), data_.size(), fill);
}

}  // namespace ssgi
