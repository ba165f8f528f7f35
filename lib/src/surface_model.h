// The surface model: what the depth buffer stands for. The march and the Embree reference both
// use it, so that comparing them measures the tracer and nothing else.
//
// The depth buffer is a triangle mesh through the pixel centres: a vertex at every surface
// pixel's centre at its planar depth z, two triangles per 2x2 quad of pixel centres with the
// fixed diagonal from (x, y) to (x+1, y+1), and a triangle only where its three vertices are
// pairwise connected (each within the other's slab, below). Inverse depth is linear across a
// triangle in screen space (it is a flat triangle in camera space), so a plane stays a plane.
// Behind the surface is a slab: the same mesh scaled by (1 + thickness) about the camera centre,
// i.e. depths from z to z * (1 + thickness). A ray hits where it enters a slab; the light it
// brings is that of the hit triangle's vertex with the largest barycentric weight. Thickness is
// relative to depth so that the model does not depend on the scene's units. Background pixels
// (z = +inf) are not vertices.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ssgi/image.h"

namespace ssgi::detail {

struct SurfaceModel {
  float thickness = 0.1f;

  // The far end of the slab of a surface at depth z.
  float slab_back(float z) const { return z * (1.0f + thickness); }

  // Whether two neighbouring vertices belong to one continuous surface: each lies within the
  // other's slab.
  bool connected(float z0, float z1) const {
    return std::isfinite(z0) && std::isfinite(z1) && z1 <= slab_back(z0) && z0 <= slab_back(z1);
  }
};

// The mesh front surface at a point of the screen.
struct MeshPoint {
  float z;    // planar depth of the surface
  int pixel;  // index (y * width + x) of the vertex whose light a hit here brings
};

// The depth buffer seen as the mesh above. Built once per frame: inverse depths and which
// triangles exist are precomputed, so a lookup is four loads and a few multiplies.
class DepthMesh {
 public:
  DepthMesh(const Image& depth, const SurfaceModel& model);

  // The surface at continuous data-window pixel coordinates (sx, sy) (pixel (x, y) has its
  // centre at (x + 0.5, y + 0.5)); false where no triangle covers the point.
  bool surface_at(float sx, float sy, MeshPoint* out) const {
    const float u = sx - 0.5f, v = sy - 0.5f;
    const float fi = std::floor(u), fj = std::floor(v);
    const int i = static_cast<int>(fi), j = static_cast<int>(fj);
    if (i < 0 || j < 0 || i + 1 >= width_ || j + 1 >= height_) return false;
    const float fu = u - fi, fv = v - fj;
    // Triangle (i,j) (i+1,j) (i+1,j+1) above the diagonal, (i,j) (i,j+1) (i+1,j+1) below.
    const bool upper = fu >= fv;
    const std::size_t quad = static_cast<std::size_t>(j) * width_ + i;
    if (!(triangles_[quad] & (upper ? kUpper : kLower))) return false;
    const int xb = upper ? i + 1 : i, yb = upper ? j : j + 1;
    const int a = j * width_ + i, b = yb * width_ + xb, c = a + width_ + 1;
    const float wa = upper ? 1.0f - fu : 1.0f - fv;
    const float wb = upper ? fu - fv : fv - fu;
    const float wc = upper ? fv : fu;
    out->z = 1.0f / (wa * inverse_depth_[a] + wb * inverse_depth_[b] + wc * inverse_depth_[c]);
    out->pixel = (wa >= wb && wa >= wc) ? a : (wb >= wc ? b : c);
    return true;
  }

  const SurfaceModel& model() const { return model_; }

 private:
  static constexpr std::uint8_t kUpper = 1, kLower = 2;
  int width_, height_;
  SurfaceModel model_;
  std::vector<float> inverse_depth_;     // 1/z per pixel
  std::vector<std::uint8_t> triangles_;  // per quad (top-left pixel index): kUpper | kLower
};

}  // namespace ssgi::detail
