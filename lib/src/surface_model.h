// The surface model: what a depth pixel stands for. The march and the Embree reference both
// use it, so that comparing them measures the tracer and nothing else.
//
// A surface pixel with planar depth z is a slab covering the pixel's footprint from z to
// z * (1 + thickness): a ray hits the pixel when the range of depths it spans over the pixel
// overlaps that slab. Thickness is relative to depth so that the model does not depend on
// the scene's units. Background pixels (z = +inf) are empty.
#pragma once

#include <cmath>

namespace ssgi::detail {

struct SurfaceModel {
  float thickness = 0.1f;

  // The far end of the slab of a pixel at depth z.
  float slab_back(float z) const { return z * (1.0f + thickness); }

  // Whether a ray spanning depths [ray_near, ray_far] over a pixel at depth z hits it.
  bool hits(float z, float ray_near, float ray_far) const {
    return std::isfinite(z) && ray_far >= z && ray_near <= slab_back(z);
  }

  // Whether two neighbouring pixels belong to one continuous surface (the reference mesh
  // connects them): each lies within the other's slab.
  bool connected(float z0, float z1) const {
    return std::isfinite(z0) && std::isfinite(z1) && z1 <= slab_back(z0) && z0 <= slab_back(z1);
  }
};

}  // namespace ssgi::detail
