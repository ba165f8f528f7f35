#include "surface_model.h"

#include "parallel.h"

namespace ssgi::detail {

DepthMesh::DepthMesh(const Image& depth, const SurfaceModel& model)
    : width_(depth.width()),
      height_(depth.height()),
      model_(model),
      inverse_depth_(depth.plane_size()),
      triangles_(depth.plane_size(), 0) {
  const float* z = depth.plane(0);
  parallel_for_rows(height_, [&](int j) {
    const std::size_t row = static_cast<std::size_t>(j) * width_;
    for (std::size_t p = row; p < row + width_; ++p) inverse_depth_[p] = 1.0f / z[p];
    if (j + 1 >= height_) return;
    for (int i = 0; i + 1 < width_; ++i) {
      const std::size_t a = static_cast<std::size_t>(j) * width_ + i;
      const float za = z[a], zr = z[a + 1], zd = z[a + width_], zc = z[a + width_ + 1];
      // Each triangle exists when its three vertices are pairwise connected.
      const bool diagonal = model_.connected(za, zc);
      std::uint8_t t = 0;
      if (diagonal && model_.connected(za, zr) && model_.connected(zr, zc)) t |= kUpper;
      if (diagonal && model_.connected(za, zd) && model_.connected(zd, zc)) t |= kLower;
      triangles_[a] = t;
    }
  });
}

}  // namespace ssgi::detail
