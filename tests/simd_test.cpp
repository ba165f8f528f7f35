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
#include "slice_kernel.h"

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

TEST(Simd, SlabSectorCoordinatesMatchTheScalarTwinBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 40; ++trial) {
    // A slice frame: origin, view vector, a direction t across it, the normal at gamma.
    const float gamma = 1.5f * u(rng);
    const float ox = u(rng), oy = u(rng), oz = 3.0f + u(rng);
    const float len = std::sqrt(ox * ox + oy * oy + oz * oz);
    const float vx = -ox / len, vy = -oy / len, vz = -oz / len;
    // t: any unit vector across v.
    float tx = vz, ty = 0, tz = -vx;
    const float tl = std::sqrt(tx * tx + tz * tz);
    tx /= tl, tz /= tl;
    const float cg = std::cos(gamma), sg = std::sin(gamma);
    const SliceFrame f{ox,
                       oy,
                       oz,
                       vx,
                       vy,
                       vz,
                       tx,
                       ty,
                       tz,
                       1.1f,
                       cg,
                       sg,
                       gamma - 0.5f * kSlicePi,
                       gamma + 0.5f * kSlicePi,
                       -0.4f,
                       20.0f,
                       0.5f * (u(rng) + 1.0f)};
    for (std::size_t n : {0u, 1u, 7u, 8u, 9u, 16u, 31u, 33u}) {
      std::vector<float> x(n), y(n), z(n);
      for (std::size_t k = 0; k < n; ++k) {
        x[k] = 4.0f * u(rng), y[k] = 4.0f * u(rng), z[k] = 5.0f + 4.0f * u(rng);
        if (k == 3) x[k] = ox, y[k] = oy, z[k] = oz;  // at the origin: a zero direction
      }
      std::vector<float> fs(n + 1, -7.0f), bs(n + 1, -7.0f), ft(n), bt(n);
      slab_sector_coordinates(f, x.data(), y.data(), z.data(), n, fs.data(), bs.data());
      slab_sector_coordinates_scalar(f, x.data(), y.data(), z.data(), n, ft.data(), bt.data());
      ASSERT_EQ(std::memcmp(fs.data(), ft.data(), n * sizeof(float)), 0) << trial << " " << n;
      ASSERT_EQ(std::memcmp(bs.data(), bt.data(), n * sizeof(float)), 0) << trial << " " << n;
      EXPECT_EQ(fs[n], -7.0f);
    }
  }
  // The coordinates span the hemisphere (here around the view vector): towards the camera is
  // its middle (half the measure), along t and against it its edges, and beyond them clamps.
  const SliceFrame f{
      0,     0,     3,    0, 0, -1, 1, 0, 0, 1.1f, 1, 0, -0.5f * kSlicePi, 0.5f * kSlicePi,
      -0.5f, 32.0f, 0.25f};
  EXPECT_NEAR(sector_coordinate(f, 0, 0, -1), 16.0f - 0.25f, 1e-4);  // towards the camera
  EXPECT_NEAR(sector_coordinate(f, 1, 0, 0), 32.0f - 0.25f, 1e-4);   // along t
  EXPECT_NEAR(sector_coordinate(f, -1, 0, 0), 0.0f - 0.25f, 1e-4);   // against t
  EXPECT_NEAR(sector_coordinate(f, 0, 0, 1), 32.0f - 0.25f, 1e-4);   // behind: clamped
}

}  // namespace
}  // namespace ssgi::detail
