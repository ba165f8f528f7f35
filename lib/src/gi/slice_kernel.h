// The slice tracer's kernel: one side of a slice marched over the trace grid's mesh, each
// sample's slab turned into the sectors it shadows (slices.h). The SIMD version does each point's
// arithmetic in the scalar twin's order (no fused multiply-add, the same polynomials), so the
// two agree bit for bit on every target; SSGI_SIMD=scalar switches to the twin.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "gi/surface_model.h"

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
// sectors' random rotation.
struct SliceFrame {
  float ox, oy, oz, vx, vy, vz, tx, ty, tz;
  float cg, sg, lo_theta, hi_theta, h_lo, to_sector, u_rot;
};

// The sector coordinate of the direction from the origin to offset (wx, wy, wz): sector k is
// the ray at coordinate k, so a slab between coordinates a <= b shadows sectors ceil(a) ..
// floor(b). Directions outside the hemisphere clamp to its bounds.
inline float sector_coordinate(const SliceFrame& f, float wx, float wy, float wz) {
  const float c = (wx * f.vx + wy * f.vy) + wz * f.vz;
  const float s = (wx * f.tx + wy * f.ty) + wz * f.tz;
  // sin^2 theta and sin theta cos theta need no square root.
  const float inv = 1.0f / (c * c + s * s);
  float theta = fast_atan2(s, c), sin2 = (s * s) * inv, sin_cos = (s * c) * inv;
  bool below_view = s < 0;  // the sign of sin theta
  if (theta < f.lo_theta)
    theta = f.lo_theta, sin2 = f.cg * f.cg, sin_cos = -(f.cg * f.sg), below_view = f.cg > 0;
  if (theta > f.hi_theta)
    theta = f.hi_theta, sin2 = f.cg * f.cg, sin_cos = -(f.cg * f.sg), below_view = f.cg < 0;
  // The slice's measure cos(theta - gamma) |sin theta| integrated from 0 to theta.
  const float g = 0.5f * (f.cg * sin2 + f.sg * (theta - sin_cos));
  const float m = below_view ? -g : g;
  return (m - f.h_lo) * f.to_sector - f.u_rot;
}

// The trace grid's mesh as the kernel reads it (surface_model.h's rules): a sample reads the
// three corners of one triangle in two neighbouring rows, so each vertex is one 8-byte texel with
// its inverse depth, its normal to 1/127 and the flags of the two triangles of the quad it is
// the top-left corner of. Samples land far apart; fewer cache lines per sample is what makes
// them fast.
struct MeshTexel {
  float inverse_depth;
  std::int8_t nx, ny, nz;
  // kUpperTriangle | kLowerTriangle, and in the bits from kThicknessShift its slab's thickness
  // code c: (kThicknessSteps - c) / kThicknessSteps of the model's (0: all of it).
  std::uint8_t triangles;
};
static_assert(sizeof(MeshTexel) == 8, "two 32-bit words, gathered as such");
constexpr std::uint8_t kUpperTriangle = 1, kLowerTriangle = 2;
constexpr int kThicknessShift = 2;
static_assert(kThicknessSteps << kThicknessShift == 256, "the code fills the byte's other bits");

// The texel code of relative thickness t, a multiple of model / kThicknessSteps (0 for model).
inline int thickness_code(float t, float model) {
  const int c = kThicknessSteps - static_cast<int>(std::lround(t / model * kThicknessSteps));
  return std::clamp(c, 0, kThicknessSteps - 1);
}

// The relative thickness a texel's code stands for.
inline float thickness_of_code(int code, float model) {
  return model * (static_cast<float>(kThicknessSteps - code) * (1.0f / kThicknessSteps));
}

struct MeshView {
  const MeshTexel* texels;
  int width, height;
};

// One side of a slice: steps samples at screen distances 1 + (t_max - 1) f^2 with f = (j +
// u_step) / steps, from (qx, qy) along the unit direction (sx, sy), in trace-grid pixels; the
// camera (cx, cy, 1/fx, 1/fy) in the same units; samples farther than sqrt(max_distance2) from
// the origin end the side (0: no limit); the model's thickness (the texels' codes scale it).
struct SideMarch {
  float qx, qy, sx, sy, t_max, u_step;
  int steps;
  float cx, cy, inv_fx, inv_fy, max_distance2, thickness;
};

// What march_side leaves per step j: bits[j], the sectors the sample's slab shadows together
// with the strip to sample j - 1 when both lie on one continuous surface (0 where the side
// meets no surface), and pixel[j + 1], the vertex whose light it brings (-1: none), marked
// kSeenFromBehind when the ray to the sample meets its surface from behind, and front_u[j + 1]
// and back_u[j + 1], the sector coordinates of its own slab's front and back (where pixel[j + 1]
// is a vertex). The other arrays are the kernel's own (index j + 1 for step j, index 0 standing
// for "no step before the first"), padded to whole vectors.
struct SideSamples {
  std::vector<float> x, y, z, nx, ny, nz, thickness, front_u, back_u, distance2;
  std::vector<std::int32_t> pixel;
  std::vector<std::uint32_t> bits;
  // Over the steps taken: the least back coordinate of the slabs whose back lies above their
  // front, and the greatest of those whose back lies below (+inf, -inf when none). A ray whose
  // sector coordinate lies above neither and below neither passes behind none of the slabs.
  float beyond_above = 0, beyond_below = 0;
  // Room for `steps` steps on any SIMD target.
  void reserve(int steps);
};

// Sets samples->beyond_above and beyond_below over the first `count` steps.
inline void bound_backs(SideSamples* samples, int count) {
  float above = std::numeric_limits<float>::infinity(), below = -above;
  for (int j = 0; j < count; ++j) {
    if (samples->pixel[j + 1] < 0) continue;
    const float front = samples->front_u[j + 1], back = samples->back_u[j + 1];
    if (back > front) above = std::min(above, back);
    if (back < front) below = std::max(below, back);
  }
  samples->beyond_above = above;
  samples->beyond_below = below;
}

// Marches one side of the slice `f` over the mesh: returns the number of steps to use (all of
// them, or up to the first sample beyond the maximum distance) with out->bits and out->pixel
// filled for those. SIMD unless SSGI_SIMD=scalar; every step's arithmetic is the scalar twin's,
// in its order.
int march_side(const MeshView& mesh, const SliceFrame& f, const SideMarch& m, SideSamples* out);

// The scalar twin, for the tests.
int march_side_scalar(const MeshView& mesh, const SliceFrame& f, const SideMarch& m,
                      SideSamples* out);

// The hits of one marched side, in order: step j's sectors not yet in *mask (fresh) join it,
// and the step is a hit of weight sector_weight x (fresh sectors) when there are any. Writes
// pixel[k] and weight[k] for k up to the steps taken (room for `count` entries), returns how
// many hits were kept. Per SIMD target for its population count (POPCNT from SSE4 on, a
// library call on the x86-64 baseline); the same integers and products as the twin.
int collect_hits(const SideSamples& samples, int count, float sector_weight, std::uint32_t* mask,
                 std::int32_t* pixel, float* weight);
int collect_hits_scalar(const SideSamples& samples, int count, float sector_weight,
                        std::uint32_t* mask, std::int32_t* pixel, float* weight);

// The number of sectors (set bits) in a mask, by bit arithmetic: __builtin_popcount is a
// library call on the x86-64 baseline (no POPCNT instruction assumed).
inline int sector_count(std::uint32_t v) {
  v = v - ((v >> 1) & 0x55555555u);
  v = (v & 0x33333333u) + ((v >> 2) & 0x33333333u);
  return static_cast<int>((((v + (v >> 4)) & 0x0f0f0f0fu) * 0x01010101u) >> 24);
}

// collect_hits with the population count `count_sectors` (inlined into each target's version).
template <typename CountSectors>
inline int collect_hits_with(const SideSamples& samples, int count, float sector_weight,
                             std::uint32_t* mask, std::int32_t* pixel, float* weight,
                             const CountSectors& count_sectors) {
  std::uint32_t m = *mask;
  int kept = 0;
  // Every step is written, and kept (the index moves on) when it brought sectors of its own: no
  // branch on data.
  for (int j = 0; j < count; ++j) {
    const std::uint32_t fresh = samples.bits[j] & ~m;
    m |= fresh;
    pixel[kept] = samples.pixel[j + 1];
    weight[kept] = sector_weight * static_cast<float>(count_sectors(fresh));
    kept += fresh != 0;
  }
  *mask = m;
  return kept;
}

// The sectors ceil(lo) .. floor(hi) of [lo, hi] as bits (0 when empty or not a number).
inline std::uint32_t sector_bits(float lo, float hi) {
  if (!(hi > lo)) return 0;
  const float k0 = std::min(std::max(std::ceil(lo), 0.0f), 32.0f);
  const float k1 = std::min(std::max(std::floor(hi), -1.0f), 31.0f);
  if (!(k0 <= k1)) return 0;
  return (~0u >> (31u - static_cast<std::uint32_t>(k1))) & (~0u << static_cast<std::uint32_t>(k0));
}

}  // namespace ssgi::detail
