// The denoiser's kernels on the range weight (how much a sample belongs to a pixel's surface),
// a row at a time: the depth gradients of a level's guides, halving a level, the joint
// bilateral filter and joint bilateral upsampling. Each SIMD kernel does every pixel's arithmetic
// in its scalar twin's order (no fused multiply-add, the same polynomials), so the two agree bit
// for bit on every target, and SSGI_SIMD=scalar switches to the twins.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "ssgi/settings.h"

namespace ssgi::detail {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Beyond this exponent a weight is below 2e-22, far under the float resolution of any sum it
// would join, so it is taken as 0 without calling exp.
constexpr float kMaxExponent = 50.0f;

// One pixel's guides: depth (+inf on background), unit normal (0 where unknown), and the
// depth change per pixel along x and y on the pixel's own surface (see `axis_gradient`).
// Stored together (24 bytes a pixel): a filter tap reads one pixel's guides at once.
struct Surface {
  float z = kInf, nx = 0, ny = 0, nz = 0, gx = 0, gy = 0;
};

inline bool is_surface(float z) { return z < kInf; }
inline bool has_normal(const Surface& s) { return s.nx != 0 || s.ny != 0 || s.nz != 0; }

struct RangeTerms {
  float inv_sigma_depth;  // 1 / relative depth difference at which the weight is exp(-1/2)
  float normal_power;
  int integer_normal_power;  // normal_power when it is a whole number up to 64, else -1
};

inline RangeTerms make_range_terms(const DenoiseSettings& s) {
  const float p = s.normal_power;
  const bool whole = p == std::floor(p) && p <= 64;
  return {1.0f / s.sigma_depth, p, whole ? static_cast<int>(p) : -1};
}

// x^p for x in [0, 1]. Whole powers (the default 32 among them) by repeated squaring, which
// is several times faster than std::pow in the innermost loop.
inline float normal_term(float x, const RangeTerms& terms) {
  int n = terms.integer_normal_power;
  if (n < 0) return std::pow(x, terms.normal_power);
  float result = 1;
  for (; n > 0; n >>= 1, x *= x) {
    if (n & 1) result *= x;
  }
  return result;
}

// exp(-e) for e in [0, kMaxExponent), to about 2e-7 relative: 2^-e log2(e) split into an
// exponent and a polynomial for 2^f on [0, 1). No libm call in the innermost loop, and the same
// bits on every platform.
inline __attribute__((always_inline)) float exp_negative(float e) {
  const float t = -e * 1.44269504f;
  const float whole = std::floor(t);
  const float f = t - whole;
  const float p =
      1.0f +
      f * (0.6931472f +
           f * (0.2402265f +
                f * (0.05550357f + f * (0.009618129f + f * (0.001333355f + f * 0.0001540353f)))));
  const std::int32_t bits = (static_cast<std::int32_t>(whole) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

// How much sample q belongs to p's surface: 1 for p itself, ~0 across an edge or a crease.
// (dx, dy) is q's position relative to p, in p's pixels.
inline __attribute__((always_inline)) float range_weight(const Surface& p, const Surface& q,
                                                         float dx, float dy,
                                                         const RangeTerms& terms) {
  // q's depth against p's extrapolated along p's screen-space depth gradient, so that a slanted
  // plane passes as one surface; relative to p's depth, so that the test does not depend on
  // the scene's scale. An overflow gives inf or NaN, which the test below rejects.
  const float dz = (q.z - p.z) - p.gx * dx - p.gy * dy;
  const float s = dz * (terms.inv_sigma_depth / p.z);  // the factor once per pixel in kernels
  const float exponent = 0.5f * s * s;
  if (!(exponent < kMaxExponent)) return 0.0f;  // also rejects NaN
  float w = exp_negative(exponent);
  const float cos_angle = p.nx * q.nx + p.ny * q.ny + p.nz * q.nz;
  if (cos_angle > 0) {
    w *= normal_term(std::min(cos_angle, 1.0f), terms);
  } else if (has_normal(p) && has_normal(q)) {
    return 0.0f;
  }
  // An unknown (zero) normal leaves the decision to depth alone.
  return w;
}

// Of two one-sided depth differences, the smaller if they agree in sign (a plane, perhaps
// with a depth edge on one side), else 0 (a ridge or a thin feature, not a plane). NaN when
// either is missing.
inline float agreeing_difference(float a, float b) {
  if (!std::isfinite(a) || !std::isfinite(b)) return std::numeric_limits<float>::quiet_NaN();
  if ((a < 0 && b > 0) || (a > 0 && b < 0)) return 0.0f;
  return std::fabs(a) <= std::fabs(b) ? a : b;
}

// Depth change per pixel at z0 along one axis, from the depths one and two pixels before and
// after it (+inf outside the image or on background). Prefers the differences on both sides
// of the pixel; at image and silhouette borders, the two on the side that exists. 0 when
// nothing agrees, which only makes the depth test stricter there.
inline float axis_gradient(float before2, float before1, float z0, float after1, float after2) {
  const float before = z0 - before1, after = after1 - z0;
  for (float g : {agreeing_difference(before, after), agreeing_difference(after, after2 - after1),
                  agreeing_difference(before1 - before2, before)}) {
    if (!std::isnan(g)) return g;
  }
  return 0.0f;
}

// Row y of the depth gradients of the w x h depths z (+inf on background): gx[x] and gy[x] for
// x in [0, w), 0 on background.
void depth_gradient_row(const float* z, int w, int h, int y, float* gx, float* gy);

// The scalar twin of depth_gradient_row, for the tests.
void depth_gradient_row_scalar(const float* z, int w, int h, int y, float* gx, float* gy);

// Pixel x of depth_gradient_row.
inline void depth_gradient_pixel(const float* z, int w, int h, int x, int y, float* gx, float* gy) {
  const std::size_t i = static_cast<std::size_t>(y) * w + x;
  if (!(z[i] < kInf)) {
    gx[x] = gy[x] = 0.0f;
    return;
  }
  auto along_x = [&](int k) { return x + k >= 0 && x + k < w ? z[i + k] : kInf; };
  auto along_y = [&](int k) {
    return y + k >= 0 && y + k < h ? z[static_cast<std::size_t>(y + k) * w + x] : kInf;
  };
  gx[x] = axis_gradient(along_x(-2), along_x(-1), z[i], along_x(1), along_x(2));
  gy[x] = axis_gradient(along_y(-2), along_y(-1), z[i], along_y(1), along_y(2));
}

// A pyramid level's guides as planes (Surface's fields, one plane each), width x height; or a
// window of its rows from y0 on, for a pass that reads a row or two at a time (the planes then
// hold only those rows; height stays the level's).
struct GuidePlanes {
  const float *z, *nx, *ny, *nz, *gx, *gy;
  int width, height;
  int y0 = 0;  // the first row the planes hold
  Surface at(std::size_t i) const { return {z[i], nx[i], ny[i], nz[i], gx[i], gy[i]}; }
  // The planes' index of pixel (x, y).
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y - y0) * width + static_cast<std::size_t>(x);
  }
};

// Weight of a fine pixel's own value in bilateral upsampling. A pixel that no coarse sample
// resembles (a feature thinner than a coarse pixel) keeps its own light instead of taking a
// neighbouring surface's. A constant blend rather than a threshold keeps neighbouring pixels
// from switching abruptly; where the coarse samples do match, it lets in 1e-3 of the noise.
constexpr float kOwnValueWeight = 1e-3f;

// Fine pixel (x, y) of upsample_row below.
inline void upsample_pixel(const GuidePlanes& fine, int x, int y, const GuidePlanes& coarse,
                           const float* const coarse_light[3], const float* const own[3],
                           const RangeTerms& terms, float* const out[3]) {
  const std::size_t i = fine.index(x, y);
  if (!is_surface(fine.z[i])) {
    for (int c = 0; c < 3; ++c) out[c][x] = 0.0f;
    return;
  }
  const Surface p = fine.at(i);
  // A fine pixel centre lies at coarse coordinate x/2 - 1/4: its two coarse samples along an
  // axis and the second's bilinear weight.
  const int first_x = x % 2 == 0 ? x / 2 - 1 : x / 2, first_y = y % 2 == 0 ? y / 2 - 1 : y / 2;
  const float second_wx = x % 2 == 0 ? 0.75f : 0.25f, second_wy = y % 2 == 0 ? 0.75f : 0.25f;
  // The sums' range: float rounding must not take a mean outside the values it averages.
  float sum = kOwnValueWeight, light[3], lo[3], hi[3];
  for (int c = 0; c < 3; ++c) light[c] = sum * own[c][x], lo[c] = hi[c] = own[c][x];
  for (int ky = 0; ky < 2; ++ky) {
    const int cy = std::clamp(first_y + ky, 0, coarse.height - 1);
    const float wy = ky ? second_wy : 1.0f - second_wy;
    for (int kx = 0; kx < 2; ++kx) {
      const int cx = std::clamp(first_x + kx, 0, coarse.width - 1);
      const float wx = kx ? second_wx : 1.0f - second_wx;
      const std::size_t j = static_cast<std::size_t>(cy) * coarse.width + cx;
      // Coarse sample centres sit at fine coordinate 2c + 1/2; a background sample weighs 0
      // (its infinite depth fails the depth test).
      const float range = range_weight(p, coarse.at(j), static_cast<float>(2 * cx - x) + 0.5f,
                                       static_cast<float>(2 * cy - y) + 0.5f, terms);
      const float wq = (wx * wy) * range;
      sum += wq;
      for (int c = 0; c < 3; ++c) {
        const float v = coarse_light[c][j];
        light[c] += wq * v;
        const float counted = wq > 0 ? v : own[c][x];
        lo[c] = std::min(lo[c], counted), hi[c] = std::max(hi[c], counted);
      }
    }
  }
  for (int c = 0; c < 3; ++c) out[c][x] = std::min(std::max(light[c] / sum, lo[c]), hi[c]);
}

// Pixel (x, y) of joint_bilateral_row below.
inline void joint_bilateral_pixel(const GuidePlanes& g, const float* const light[3], int x, int y,
                                  int radius, const float* taps, const RangeTerms& terms,
                                  float* const out[3]) {
  const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
  if (!is_surface(g.z[i])) {
    for (int c = 0; c < 3; ++c) out[c][x] = 0.0f;
    return;
  }
  const Surface p = g.at(i);
  float weight_sum = 0, sum[3] = {0, 0, 0}, lo[3] = {kInf, kInf, kInf},
        hi[3] = {-kInf, -kInf, -kInf};
  for (int qy = std::max(0, y - radius); qy <= std::min(g.height - 1, y + radius); ++qy) {
    for (int qx = std::max(0, x - radius); qx <= std::min(g.width - 1, x + radius); ++qx) {
      const std::size_t j = static_cast<std::size_t>(qy) * g.width + qx;
      const float spatial = taps[std::abs(qx - x)] * taps[std::abs(qy - y)];
      // p itself counts fully, so that the sum is never 0; background weighs 0.
      const float range = j == i ? 1.0f
                                 : range_weight(p, g.at(j), static_cast<float>(qx - x),
                                                static_cast<float>(qy - y), terms);
      const float wq = spatial * range;
      if (!(wq > 0)) continue;
      weight_sum += wq;
      for (int c = 0; c < 3; ++c) {
        const float v = light[c][j];
        sum[c] += wq * v;
        lo[c] = std::min(lo[c], v), hi[c] = std::max(hi[c], v);
      }
    }
  }
  for (int c = 0; c < 3; ++c) out[c][x] = std::min(std::max(sum[c] / weight_sum, lo[c]), hi[c]);
}

// Row y of the joint bilateral filter of `light` (3 planes, finite) guided by `g`: a square
// window of `radius`, spatial weights taps[|dx|] taps[|dy|] times range_weight, the mean
// clamped to the range of the values it averages; out[c][x] for x in [0, g.width), 0 on
// background.
void joint_bilateral_row(const GuidePlanes& g, const float* const light[3], int y, int radius,
                         const float* taps, const RangeTerms& terms, float* const out[3]);

// The scalar twin of joint_bilateral_row, for the tests.
void joint_bilateral_row_scalar(const GuidePlanes& g, const float* const light[3], int y,
                                int radius, const float* taps, const RangeTerms& terms,
                                float* const out[3]);

// A row of a coarser level's guides being written (no gradients: they follow from the depths).
struct GuideRow {
  float *z, *nx, *ny, *nz;
};

// Coarse pixel (x, y) of downsample_row below.
inline void downsample_pixel(const GuidePlanes& fine, const float* const fine_light[3], int x,
                             int y, const RangeTerms& terms, const GuideRow& out,
                             float* const light_out[3]) {
  // The block's surface samples in the order (2x, 2y), (2x+1, 2y), (2x, 2y+1), (2x+1, 2y+1).
  std::size_t index[4];
  int block[4];  // 0..3: bit 0 the sample's column in the block, bit 1 its row
  float depths[4];
  int count = 0;
  for (int k = 0; k < 4; ++k) {
    const int fx = 2 * x + (k & 1), fy = 2 * y + (k >> 1);
    if (fx >= fine.width || fy >= fine.height) continue;
    const std::size_t j = fine.index(fx, fy);
    if (!is_surface(fine.z[j])) continue;
    index[count] = j, block[count] = k, depths[count] = fine.z[j];
    ++count;
  }
  if (count == 0) {  // background
    out.z[x] = kInf;
    out.nx[x] = out.ny[x] = out.nz[x] = 0.0f;
    if (light_out[0])
      for (int c = 0; c < 3; ++c) light_out[c][x] = 0.0f;
    return;
  }
  // The representative: the sample nearest the median depth, so that the surface covering most
  // of the block wins; on a tie the nearer one, since thin foreground features are the first
  // to vanish from a pyramid.
  float sorted[4] = {kInf, kInf, kInf, kInf};
  for (int s = 0; s < count; ++s) {  // insertion sort of at most 4
    int k = s;
    for (; k > 0 && sorted[k - 1] > depths[s]; --k) sorted[k] = sorted[k - 1];
    sorted[k] = depths[s];
  }
  const float median =
      count % 2 ? sorted[count / 2] : 0.5f * sorted[count / 2 - 1] + 0.5f * sorted[count / 2];
  int r = 0;
  for (int s = 1; s < count; ++s) {
    const float d = std::fabs(depths[s] - median), best = std::fabs(depths[r] - median);
    if (d < best || (d == best && depths[s] < depths[r])) r = s;
  }
  const Surface rep = fine.at(index[r]);
  // The samples weighted by their resemblance to the representative; depths moved to the
  // block centre (2x + 1/2, 2y + 1/2) along the representative's gradient.
  const float centre_x = 2.0f * static_cast<float>(x) + 0.5f;
  const float centre_y = 2.0f * static_cast<float>(y) + 0.5f;
  float weight_sum = 0, z = 0, nx = 0, ny = 0, nz = 0, light[3] = {0, 0, 0};
  float lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  for (int s = 0; s < count; ++s) {
    const std::size_t j = index[s];
    const int bx = block[s] & 1, by = block[s] >> 1, rx = block[r] & 1, ry = block[r] >> 1;
    const float wq = s == r ? 1.0f
                            : range_weight(rep, fine.at(j), static_cast<float>(bx - rx),
                                           static_cast<float>(by - ry), terms);
    if (!(wq > 0)) continue;
    weight_sum += wq;
    const float sx = static_cast<float>(2 * x + bx), sy = static_cast<float>(2 * y + by);
    z += wq * (fine.z[j] + rep.gx * (centre_x - sx) + rep.gy * (centre_y - sy));
    nx += wq * fine.nx[j];
    ny += wq * fine.ny[j];
    nz += wq * fine.nz[j];
    if (fine_light[0])
      for (int c = 0; c < 3; ++c) {
        const float v = fine_light[c][j];
        light[c] += wq * v;
        lo[c] = std::min(lo[c], v), hi[c] = std::max(hi[c], v);
      }
  }
  // weight_sum >= 1, the representative's own weight. Moving a depth along a steep gradient
  // could in theory take it behind the camera or beyond float range.
  z = z / weight_sum;
  out.z[x] = z > 0 && z < kInf ? z : rep.z;
  const float length = std::sqrt(nx * nx + ny * ny + nz * nz);
  const bool normal = length > 0 && length < kInf;
  out.nx[x] = normal ? nx / length : 0.0f;
  out.ny[x] = normal ? ny / length : 0.0f;
  out.nz[x] = normal ? nz / length : 0.0f;
  if (light_out[0])
    for (int c = 0; c < 3; ++c)
      light_out[c][x] = std::min(std::max(light[c] / weight_sum, lo[c]), hi[c]);
}

// Row y of halving a level (rounding up): each 2x2 block of `fine` becomes the weighted mean
// of its surface samples, weighted by their resemblance to the block's representative, so that
// a block on an edge keeps one surface instead of a blend of two; its light, when fine_light[0]
// is not null, likewise (clamped to the range of the values it averages). Writes x in [0,
// coarse_width) of `out` (and light_out when there is light).
void downsample_row(const GuidePlanes& fine, const float* const fine_light[3], int y,
                    int coarse_width, const RangeTerms& terms, const GuideRow& out,
                    float* const light_out[3]);

// The scalar twin of downsample_row, for the tests.
void downsample_row_scalar(const GuidePlanes& fine, const float* const fine_light[3], int y,
                           int coarse_width, const RangeTerms& terms, const GuideRow& out,
                           float* const light_out[3]);

// Row y of joint bilateral upsampling (Kopf et al. 2007) from the level `coarse` (its light
// `coarse_light`, 3 planes) to the next finer level `fine`: each fine pixel takes its 4 nearest
// coarse samples with bilinear weights times their range_weight, plus kOwnValueWeight of its
// own value own[c][x], clamped to the range of the values it averages; out[c][x] for x in
// [0, fine.width), 0 where the fine pixel has no surface (own, and the coarse light where a
// coarse sample has a surface, must be finite). SIMD unless SSGI_SIMD=scalar or the normal power is
// not a whole number (std::pow has no SIMD twin here).
void upsample_row(const GuidePlanes& fine, int y, const GuidePlanes& coarse,
                  const float* const coarse_light[3], const float* const own[3],
                  const RangeTerms& terms, float* const out[3]);

// The scalar twin of upsample_row, for the tests.
void upsample_row_scalar(const GuidePlanes& fine, int y, const GuidePlanes& coarse,
                         const float* const coarse_light[3], const float* const own[3],
                         const RangeTerms& terms, float* const out[3]);

// Whether every kernel runs its scalar twin: set_simd_target("scalar") or SSGI_SIMD=scalar.
bool simd_forced_scalar();

}  // namespace ssgi::detail
