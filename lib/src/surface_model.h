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

// The depth buffer seen as the mesh above.
class DepthMesh {
 public:
  DepthMesh(const Image& depth, const SurfaceModel& model) : depth_(depth), model_(model) {}

  // The surface at continuous data-window pixel coordinates (sx, sy) (pixel (x, y) has its
  // centre at (x + 0.5, y + 0.5)); false where no triangle covers the point.
  bool surface_at(float sx, float sy, MeshPoint* out) const {
    const float u = sx - 0.5f, v = sy - 0.5f;
    const float fi = std::floor(u), fj = std::floor(v);
    const int i = static_cast<int>(fi), j = static_cast<int>(fj);
    if (i < 0 || j < 0 || i + 1 >= depth_.width() || j + 1 >= depth_.height()) return false;
    const float fu = u - fi, fv = v - fj;
    // Triangle (i,j) (i+1,j) (i+1,j+1) above the diagonal, (i,j) (i,j+1) (i+1,j+1) below.
    const bool upper = fu >= fv;
    const int xb = upper ? i + 1 : i, yb = upper ? j : j + 1;
    const float za = depth_.at(0, i, j), zb = depth_.at(0, xb, yb),
                zc = depth_.at(0, i + 1, j + 1);
    if (!model_.connected(za, zb) || !model_.connected(zb, zc) || !model_.connected(za, zc))
      return false;
    const float wa = upper ? 1.0f - fu : 1.0f - fv;
    const float wb = upper ? fu - fv : fv - fu;
    const float wc = upper ? fv : fu;
    out->z = 1.0f / (wa / za + wb / zb + wc / zc);
    const int w = depth_.width();
    if (wa >= wb && wa >= wc)
      out->pixel = j * w + i;
    else if (wb >= wc)
      out->pixel = yb * w + xb;
    else
      out->pixel = (j + 1) * w + i + 1;
    return true;
  }

  const SurfaceModel& model() const { return model_; }

 private:
  const Image& depth_;
  SurfaceModel model_;
};

}  // namespace ssgi::detail
