// Stochastic hemisphere directions: animated Interleaved Gradient Noise rotating a
// low-discrepancy sequence, mapped to cosine-weighted directions around the normal.
#pragma once

#include <Imath/ImathVec.h>

#include <cstdint>

namespace ssgi::detail {

// Per-pixel random rotation of the ray set, a pure function of the display-window pixel,
// the frame and the seed (never of the data window, threads or crops).
struct PixelNoise {
  double u1, u2, jitter;
};
PixelNoise pixel_noise(int display_x, int display_y, int frame, std::uint32_t seed);

// Interleaved Gradient Noise (Jimenez 2014) at a continuous pixel position, in [0, 1).
double interleaved_gradient_noise(double x, double y);

// Sample `k` of the per-pixel set: the R2 sequence (Roberts 2018) point k, rotated by `noise`
// (Cranley-Patterson), so that a pixel's rays are stratified and neighbouring pixels differ.
void ray_sample(const PixelNoise& noise, int k, float* u1, float* u2, float* jitter);

// SplitMix64's finaliser: a 64-bit hash for random choices that are pure functions of their
// inputs (pixel, frame, seed, ray), whatever the thread or chunk.
inline std::uint64_t mix64(std::uint64_t h) {
  h += 0x9E3779B97F4A7C15ull;
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

// A uniform float in [0, 1) from a hash's top 24 bits.
inline float unit_float(std::uint64_t h) {
  return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

// Cosine-weighted direction around the unit normal `n` from two uniforms (Malley's method,
// with the branchless orthonormal basis of Duff et al. 2017).
Imath::V3f cosine_hemisphere(const Imath::V3f& n, float u1, float u2);

}  // namespace ssgi::detail
