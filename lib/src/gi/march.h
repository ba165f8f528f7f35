// Screen-space ray march: hemisphere rays from every surface pixel, marched through the depth
// buffer (the surface model of surface_model.h) until they hit a pixel or miss.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "gi/directions.h"
#include "gi/environment.h"
#include "gi/misses.h"
#include "gi/surface_model.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// Ray geometry shared by the march and the Embree reference. A ray heading towards the camera
// ends where it reaches this fraction of its origin's depth (nothing nearer is in the depth
// buffer's view); an unlimited ray ends this many origin depths away (its projection is then
// within a fraction of a pixel of the vanishing point).
constexpr float kNearFraction = 1e-3f;
constexpr float kFarFactor = 1e6f;
// A ray does not hit its own pixel: where it leaves the pixel's square inside a slab, the hit
// is taken this far (in pixels) past the square's edge.
constexpr float kPastEdgePx = 1e-3f;

// A ray's screen segment: data-window pixel position s0 + f (s1 - s0) and inverse depth
// h0 + f (h1 - h0) (linear in screen space), for f in [f_lo, f_hi].
struct ScreenSegment {
  float sx0, sy0, dx, dy, h0, h1, f_lo, f_hi;
};

// Narrows [f_lo, f_hi] to the part of the segment inside [0, width] x [0, height]
// (Liang-Barsky); false when nothing of it is.
bool clip_to_window(ScreenSegment* s, float width, float height);

// The pixel whose light the segment's first hit on `mesh` brings, or -1, never pixel (self_x,
// self_y) (the ray's own; -1, -1 for none). A segment up to `max_steps` pixels long walks every
// triangle it crosses and solves where it enters a slab (the surface model itself, which the Embree
// reference traces too); a longer one samples `max_steps` evenly spaced points, offset by
// `jitter` in [0, 1) of a step, and can step over a thin slab.
int march_segment(const DepthMesh& mesh, const ScreenSegment& s, int max_steps, float jitter,
                  int self_x, int self_y);

// The hemisphere rays of surface pixel (x, y) (data window): the origin is the pixel centre at
// its depth, offset along the normal by start_offset x depth; ray k's direction and march
// jitter come from the pixel's noise. The march and the Embree reference both use it, so ray k
// of one is ray k of the other.
class PixelRays {
 public:
  PixelRays(const GBuffer& g, const GiSettings& settings, int x, int y);
  const Imath::V3f& origin() const { return origin_; }
  // Ray k's unit direction; its march jitter in [0, 1) in *jitter.
  Imath::V3f direction(int k, float* jitter) const;

 private:
  Imath::V3f origin_, normal_;
  PixelNoise noise_;
};

// A hit on pixel `hit` (>= 0, data window) of a ray from camera-space `origin`, marked when the
// ray meets it from behind (surface_model.h).
std::int32_t mark_hit(const GBuffer& g, std::int32_t hit, const Imath::V3f& origin);

// Where each ray of each pixel ended, kept so that further bounces re-gather without
// re-marching: the hit pixel's index (y * width + x, data window; kSeenFromBehind marks a hit from
// behind) or -1 for a miss, and per pixel the number of missing rays and the sums of what the
// miss model gives them (MissModel::add, weight 1 each).
struct RayHits {
  int rays = 0;
  std::vector<std::int32_t> hit;  // width * height * rays
  Image env_sum;                  // 3 channels
  Image cube_sum;                 // kCubeFaces channels
  Image miss_count;               // 1 channel
  // Sized for `g` with `rays` rays per pixel, every ray a miss until traced.
  RayHits(const GBuffer& g, int rays);
  RayHits() = default;
  // Stores pixel p's misses: their count and the sums of what they bring.
  void store_misses(std::size_t p, int count, const float env[3], const float cube[kCubeFaces]);
};

// Marches settings.rays rays per surface pixel and records their ends.
RayHits march_screen_space(const GBuffer& g, const GiSettings& settings, const MissModel& misses);

}  // namespace ssgi::detail
