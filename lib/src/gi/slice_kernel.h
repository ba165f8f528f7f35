// The slice tracer's arithmetic kernel: for a batch of sample points on one slice, where their
// slabs' two ends fall among the slice's sectors (slices.h). The SIMD version does each point's
// arithmetic in the scalar twin's order (no fused multiply-add, the same polynomials), so the
// two agree bit for bit on every target; SSGI_SIMD=scalar switches to the twin.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace ssgi::detail {

constexpr float kSlicePi = 3.14159265358979f;

// atan2 to about 1e-5 rad with a polynomial (no libm call in the inner loop; the same bits on
// every platform).
inline float fast_atan2(float y, float x) {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  if (hi == 0) return 0.0f;
  const float a = lo / hi, s = a * a;
  // Minimax polynomial for atan on [0, 1].
  float r =
      ((((((-0.0040540580f * s + 0.0218612288f) * s - 0.0559098861f) * s + 0.0964200441f) * s -
         0.1390853351f) *
            s +
        0.1994653599f) *
           s -
       0.3332985605f) *
          s * a +
      a;
  if (ay > ax) r = 0.5f * kSlicePi - r;
  if (x < 0) r = kSlicePi - r;
  return y < 0 ? -r : r;
}

// What a slice's sector coordinates depend on: the origin, the view vector and the slice's
// direction t across it, the normal's angle gamma in the slice (cos, sin), the hemisphere's
// bounds gamma -+ pi/2, the measure at the lower bound, sectors per unit measure and the
// sectors' random rotation; back_scale = 1 + thickness.
struct SliceFrame {
  float ox, oy, oz, vx, vy, vz, tx, ty, tz;
  float back_scale, cg, sg, lo_theta, hi_theta, h_lo, to_sector, u_rot;
};

// The sector coordinate of the direction from the origin to offset (wx, wy, wz): sector k is
// the ray at coordinate k, so a slab between coordinates a <= b shadows sectors ceil(a) ..
// floor(b). Directions outside the hemisphere clamp to its bounds.
inline float sector_coordinate(const SliceFrame& f, float wx, float wy, float wz) {
  const float c = (wx * f.vx + wy * f.vy) + wz * f.vz;
  const float s = (wx * f.tx + wy * f.ty) + wz * f.tz;
  const float inv = 1.0f / std::sqrt(c * c + s * s);
  float theta = fast_atan2(s, c), sn = s * inv, cs = c * inv;
  if (theta < f.lo_theta) theta = f.lo_theta, sn = -f.cg, cs = f.sg;
  if (theta > f.hi_theta) theta = f.hi_theta, sn = f.cg, cs = -f.sg;
  // The slice's measure cos(theta - gamma) |sin theta| integrated from 0 to theta.
  const float g = 0.5f * ((f.cg * sn) * sn + f.sg * (theta - sn * cs));
  const float m = sn < 0 ? -g : g;
  return (m - f.h_lo) * f.to_sector - f.u_rot;
}

// For points (x[k], y[k], z[k]) (the fronts of slabs, camera space), the sector coordinates of
// the front and of the back (the point scaled by back_scale). SIMD unless SSGI_SIMD=scalar.
void slab_sector_coordinates(const SliceFrame& f, const float* x, const float* y, const float* z,
                             std::size_t n, float* front, float* back);

// The scalar twin, for the tests.
void slab_sector_coordinates_scalar(const SliceFrame& f, const float* x, const float* y,
                                    const float* z, std::size_t n, float* front, float* back);

}  // namespace ssgi::detail
