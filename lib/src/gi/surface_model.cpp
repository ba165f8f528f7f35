#include "gi/surface_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel.h"

namespace ssgi::detail {

Image feature_thickness(const Image& depth, const Image& normal, float fx, float fy, float cx,
                        float cy, const SurfaceModel& model) {
  const int w = depth.width(), h = depth.height();
  const float* z = depth.plane(0);
  // Whether neighbours a and b lie on one smooth surface: each within kSmoothTolerance of its
  // depth of the other's tangent plane (a plane at any slant passes; a depth step or a crease
  // does not).
  auto smooth = [&](int ia, int ja, int ib, int jb) {
    const std::size_t a = static_cast<std::size_t>(ja) * w + ia;
    const std::size_t b = static_cast<std::size_t>(jb) * w + ib;
    if (!std::isfinite(z[a]) || !std::isfinite(z[b])) return false;
    const float d[3] = {(ib - ia) / fx * z[b] + (ia + 0.5f - cx) / fx * (z[b] - z[a]),
                        -(jb - ja) / fy * z[b] + (cy - (ja + 0.5f)) / fy * (z[b] - z[a]),
                        z[b] - z[a]};  // point b - point a
    float da = 0, db = 0;
    for (int c = 0; c < 3; ++c) {
      da += normal.plane(c)[a] * d[c];
      db += normal.plane(c)[b] * d[c];
    }
    return std::fabs(da) <= kSmoothTolerance * z[a] && std::fabs(db) <= kSmoothTolerance * z[b];
  };
  // Each pixel's run of smooth neighbours across and down.
  std::vector<int> across(depth.plane_size()), down(depth.plane_size());
  parallel_for_rows(h, [&](int j) {
    int* run = across.data() + static_cast<std::size_t>(j) * w;
    for (int i = 1, start = 0; i <= w; ++i)
      if (i == w || !smooth(i - 1, j, i, j)) {
        std::fill(run + start, run + i, i - start);
        start = i;
      }
  });
  parallel_for_rows(w, [&](int i) {
    for (int j = 1, start = 0; j <= h; ++j)
      if (j == h || !smooth(i, j - 1, i, j)) {
        for (int k = start; k < j; ++k) down[static_cast<std::size_t>(k) * w + i] = j - start;
        start = j;
      }
  });
  Image out(w, h, 1);
  const float step = model.thickness / kThicknessSteps;
  const float per_pixel = kDepthPerWidth / std::min(fx, fy);
  for (std::size_t p = 0; p < depth.plane_size(); ++p) {
    const float t = per_pixel * static_cast<float>(std::min(across[p], down[p]));
    out.plane(0)[p] = t >= model.thickness ? model.thickness : step * std::ceil(t / step);
  }
  return out;
}

Image feature_thickness(const GBuffer& g, const SurfaceModel& model) {
  const Camera& cam = g.camera;
  return feature_thickness(
      g.depth, g.normal, static_cast<float>(cam.fx), static_cast<float>(cam.fy),
      static_cast<float>(cam.cx - (g.data_window.x0 - g.display_window.x0)),
      static_cast<float>(cam.cy - (g.data_window.y0 - g.display_window.y0)), model);
}

template <typename Connect>
void DepthMesh::set_triangles(int j, const Connect& connect) {
  const std::size_t row = static_cast<std::size_t>(j) * width_;
  for (int i = 0; i + 1 < width_; ++i) {
    const std::size_t a = row + i, r = a + 1, d = a + width_, c = a + width_ + 1;
    const bool diagonal = connect(a, c);
    std::uint8_t t = 0;
    if (diagonal && connect(a, r) && connect(r, c)) t |= kUpper;
    if (diagonal && connect(a, d) && connect(d, c)) t |= kLower;
    triangles_[a] = t;
  }
}

DepthMesh::DepthMesh(const Image& depth, const Image& thickness)
    : width_(depth.width()),
      height_(depth.height()),
      thickness_(thickness.plane(0), thickness.plane(0) + thickness.plane_size()),
      inverse_depth_(depth.plane_size()),
      inverse_back_(depth.plane_size()),
      triangles_(depth.plane_size(), 0) {
  const float* z = depth.plane(0);
  parallel_for_rows(height_, [&](int j) {
    const std::size_t row = static_cast<std::size_t>(j) * width_;
    for (std::size_t p = row; p < row + width_; ++p) {
      inverse_depth_[p] = 1.0f / z[p];
      inverse_back_[p] = 1.0f / slab_back(z[p], static_cast<int>(p));
    }
    if (j + 1 >= height_) return;
    set_triangles(j, [&](std::size_t p, std::size_t q) {
      return connected(z[p], static_cast<int>(p), z[q], static_cast<int>(q));
    });
  });
}

void DepthMesh::bound_quads() {
  const float inf = std::numeric_limits<float>::infinity();
  quad_front_.assign(inverse_depth_.size(), -inf);
  quad_back_.assign(inverse_depth_.size(), inf);
  parallel_for_rows(height_ - 1, [&](int j) {
    for (int i = 0; i + 1 < width_; ++i) {
      const std::size_t a = static_cast<std::size_t>(j) * width_ + i, c = a + width_ + 1;
      const std::uint8_t t = triangles_[a];
      if (!t) continue;
      // The corners of the triangles there: both ends of the diagonal, and each one's third.
      float front = std::max(inverse_depth_[a], inverse_depth_[c]);
      float back = std::min(inverse_back_[a], inverse_back_[c]);
      for (const std::size_t third : {a + 1, a + width_}) {
        if (!(t & (third == a + 1 ? kUpper : kLower))) continue;
        front = std::max(front, inverse_depth_[third]);
        back = std::min(back, inverse_back_[third]);
      }
      quad_front_[a] = front;
      quad_back_[a] = back;
    }
  });
  tiles_x_ = (width_ - 1 + kTile - 1) / kTile;
  tiles_y_ = (height_ - 1 + kTile - 1) / kTile;
  tile_front_.assign(static_cast<std::size_t>(tiles_x_) * tiles_y_, -inf);
  tile_back_.assign(tile_front_.size(), inf);
  parallel_for_rows(tiles_y_, [&](int tj) {
    for (int ti = 0; ti < tiles_x_; ++ti) {
      const std::size_t t = static_cast<std::size_t>(tj) * tiles_x_ + ti;
      for (int j = tj * kTile; j < std::min((tj + 1) * kTile, height_ - 1); ++j)
        for (int i = ti * kTile; i < std::min((ti + 1) * kTile, width_ - 1); ++i) {
          const std::size_t q = static_cast<std::size_t>(j) * width_ + i;
          tile_front_[t] = std::max(tile_front_[t], quad_front_[q]);
          tile_back_[t] = std::min(tile_back_[t], quad_back_[q]);
        }
    }
  });
}

void DepthMesh::join_tangent_neighbours(const Image& depth, const Image& normal, float fx, float fy,
                                        float cx, float cy) {
  const float* z = depth.plane(0);
  const auto point = [&](std::size_t p) {
    const float sx = static_cast<float>(p % width_) + 0.5f;
    const float sy = static_cast<float>(p / width_) + 0.5f;
    return Imath::V3f((sx - cx) / fx * z[p], (cy - sy) / fy * z[p], z[p]);
  };
  const auto n = [&](std::size_t p) {
    return Imath::V3f(normal.plane(0)[p], normal.plane(1)[p], normal.plane(2)[p]);
  };
  parallel_for_rows(height_ - 1, [&](int j) {
    set_triangles(j, [&](std::size_t p, std::size_t q) {
      if (connected(z[p], static_cast<int>(p), z[q], static_cast<int>(q))) return true;
      if (!std::isfinite(z[p]) || !std::isfinite(z[q])) return false;
      const Imath::V3f a = point(p), b = point(q);
      return std::fabs((b - a).dot(n(p))) <= kSmoothTolerance * z[p] &&
             std::fabs((a - b).dot(n(q))) <= kSmoothTolerance * z[q];
    });
  });
}

}  // namespace ssgi::detail
