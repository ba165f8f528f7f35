#include "gi/directions.h"

#include <cmath>

namespace ssgi::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

double fract(double v) { return v - std::floor(v); }

// A small integer hash (Wang/Jenkins style) that spreads the seed over pixel offsets.
std::uint32_t hash_u32(std::uint32_t v) {
  v ^= v >> 16;
  v *= 0x7feb352dU;
  v ^= v >> 15;
  v *= 0x846ca68bU;
  v ^= v >> 16;
  return v;
}

}  // namespace

double interleaved_gradient_noise(double x, double y) {
  return fract(52.9829189 * fract(0.06711056 * x + 0.00583715 * y));
}

PixelNoise pixel_noise(int display_x, int display_y, int frame, std::uint32_t seed) {
  // Animated IGN: shift by 5.588238 px per frame over a 64-frame cycle (Jimenez 2014), plus a
  // seed-dependent offset so that different seeds give independent noise (seed 0: none).
  const std::uint32_t h = seed == 0 ? 0 : hash_u32(seed);
  const int cycle = ((frame % 64) + 64) % 64;
  const double x = display_x + 5.588238 * cycle + static_cast<double>(h & 0xfffu);
  const double y = display_y + 5.588238 * cycle + static_cast<double>((h >> 12) & 0xfffu);
  // Three decorrelated draws: IGN at offsets that are not multiples of its gradient period.
  return {interleaved_gradient_noise(x, y), interleaved_gradient_noise(y + 37.3, x + 11.9),
          interleaved_gradient_noise(x + 73.7, y + 97.1)};
}

void ray_sample(const PixelNoise& noise, int k, float* u1, float* u2, float* jitter) {
  constexpr double kR2a = 0.7548776662466927;  // 1 / plastic constant
  constexpr double kR2b = 0.5698402909980532;  // 1 / plastic constant^2
  constexpr double kGolden = 0.6180339887498949;
  *u1 = static_cast<float>(fract(noise.u1 + kR2a * k));
  *u2 = static_cast<float>(fract(noise.u2 + kR2b * k));
  *jitter = static_cast<float>(fract(noise.jitter + kGolden * k));
}

Imath::V3f cosine_hemisphere(const Imath::V3f& n, float u1, float u2) {
  const float r = std::sqrt(u1);
  const float phi = static_cast<float>(2.0 * kPi) * u2;
  const float lx = r * std::cos(phi);
  const float ly = r * std::sin(phi);
  const float lz = std::sqrt(std::fmax(0.0f, 1.0f - u1));
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  const Imath::V3f t{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
  const Imath::V3f bt{b, sign + n.y * n.y * a, -n.y};
  return lx * t + ly * bt + lz * n;
}

}  // namespace ssgi::detail
