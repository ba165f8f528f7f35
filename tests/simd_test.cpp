// Every SIMD kernel against its scalar twin: bit for bit, on odd sizes (every tail length) and
// on the values that take the kernels' other branches (background, NaN, unknown normals,
// back-facing normals, overflowing depth differences).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "range_weights.h"

namespace ssgi::detail {
namespace {

Surface random_surface(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 19);
  Surface s;
  s.z = 1.0f + 10.0f * (u(rng) + 1.0f);
  float nx = u(rng), ny = u(rng), nz = u(rng);
  const float len = std::sqrt(nx * nx + ny * ny + nz * nz);
  s.nx = nx / len, s.ny = ny / len, s.nz = nz / len;
  s.gx = 0.1f * u(rng), s.gy = 0.1f * u(rng);
  switch (pick(rng)) {  // the rare values, each about 1 in 20
    case 0:
      s.nx = s.ny = s.nz = 0;  // unknown normal
      break;
    case 1:
      s.z = std::numeric_limits<float>::quiet_NaN();
      break;
    case 2:
      s.z = std::numeric_limits<float>::infinity();
      break;
    case 3:
      s.gx = 3e38f;  // the extrapolated depth overflows
      break;
    case 4:
      s.z = 1e-30f;
      break;
    default:
      break;
  }
  return s;
}

TEST(Simd, RangeWeightsMatchTheScalarTwinBitForBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> offset(-3.0f, 3.0f);
  for (const float power : {32.0f, 1.0f, 0.0f, 7.0f}) {
    DenoiseSettings settings;
    settings.normal_power = power;
    const RangeTerms terms = make_range_terms(settings);
    for (std::size_t n = 0; n <= 37; ++n) {
      RangeBatch batch;
      batch.resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        const Surface p = random_surface(rng);
        // Half the samples near p's own surface, so that the weights are not all ~0.
        Surface q = (k % 2) ? random_surface(rng) : p;
        if (k % 2 == 0) q.z *= 1.0f + 0.01f * offset(rng);
        batch.set(k, p, q, offset(rng), offset(rng));
      }
      std::vector<float> simd(n + 1, -1.0f), scalar(n + 1, -2.0f);
      range_weights(batch, terms, simd.data());
      range_weights_scalar(batch, terms, scalar.data());
      ASSERT_EQ(std::memcmp(simd.data(), scalar.data(), n * sizeof(float)), 0)
          << "n " << n << ", power " << power;
      EXPECT_EQ(simd[n], -1.0f);  // nothing written past the batch
      std::size_t positive = 0;
      for (std::size_t k = 0; k < n; ++k) positive += scalar[k] > 0.5f;
      if (n >= 8 && power == 32.0f) EXPECT_GT(positive, 0u) << n;  // not a trivial batch
    }
  }
}

}  // namespace
}  // namespace ssgi::detail
