// The denoise pyramid: constants stay constant, noise falls, edges and background hold, and
// any size, any value and any thread count give a finite, reproducible result.
#include "gi/denoise.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "ssgi/error.h"

namespace ssgi::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Scene {
  Image light, depth, normal;
  Scene(int w, int h) : light(w, h, 3), depth(w, h, 1), normal(w, h, 3) {}

  void set(int x, int y, float value, float z, float nx, float ny, float nz) {
    for (int c = 0; c < 3; ++c) light.at(c, x, y) = value;
    depth.at(0, x, y) = z;
    normal.at(0, x, y) = nx;
    normal.at(1, x, y) = ny;
    normal.at(2, x, y) = nz;
  }
  void set_background(int x, int y, float value = 0) { set(x, y, value, kInf, 0, 0, 0); }
};

// A uniform number in [0, 1) from the generator's bits alone: std::uniform_real_distribution
// is not the same sequence on every standard library.
float uniform(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * 0x1p-24f; }

// A plane seen at an angle: 1/z is affine in screen coordinates for any plane. Depth grows
// 8x across the image; at 128x128 it changes by up to 4.5% per pixel along x in the far
// corner, as a floor seen at a grazing angle does.
float slanted_depth(int x, int y, int w, int h) {
  return 1.0f / (1.0f - 0.75f * x / w - 0.125f * y / h);
}

// A plane with light `value` (+ noise of that amplitude when `noise` > 0) on every pixel.
Scene plane(int w, int h, bool slanted, float value, float noise = 0, std::uint32_t seed = 1) {
  std::mt19937 rng(seed);
  Scene s(w, h);
  const float n = 1 / std::sqrt(1 + 0.3f * 0.3f);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float v = value + (noise > 0 ? noise * (uniform(rng) - 0.5f) : 0.0f);
      if (slanted) {
        s.set(x, y, v, slanted_depth(x, y, w, h), -0.3f * n, 0, -n);
      } else {
        s.set(x, y, v, 2.0f, 0, 0, -1);
      }
    }
  }
  return s;
}

Image denoise(const Scene& s, const DenoiseSettings& settings = {}) {
  return denoise_pyramid(s.light, s.depth, s.normal, settings);
}

bool all_finite(const Image& image) {
  return std::all_of(image.data().begin(), image.data().end(),
                     [](float v) { return std::isfinite(v); });
}

// Variance of channel 0 over the whole image.
double variance(const Image& image) {
  double sum = 0, sum2 = 0;
  const std::size_t n = image.plane_size();
  for (std::size_t i = 0; i < n; ++i) sum += image.plane(0)[i];
  const double mean = sum / n;
  for (std::size_t i = 0; i < n; ++i)
    sum2 += (image.plane(0)[i] - mean) * (image.plane(0)[i] - mean);
  return sum2 / n;
}

// Largest and smallest value over the pixels where `select(x, y)` holds, all channels.
std::pair<float, float> range_where(const Image& image,
                                    const std::function<bool(int, int)>& select) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (int c = 0; c < image.channels(); ++c) {
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        if (!select(x, y)) continue;
        lo = std::min(lo, image.at(c, x, y));
        hi = std::max(hi, image.at(c, x, y));
      }
    }
  }
  return {lo, hi};
}

TEST(Denoise, ConstantOnAPlaneStaysConstant) {
  // Every output pixel is a normalised weighted mean (accumulated in double): a constant comes
  // back to within float rounding.
  for (bool slanted : {false, true}) {
    for (auto [w, h] : {std::pair{64, 48}, std::pair{37, 23}}) {
      for (int levels = 0; levels <= 3; ++levels) {
        SCOPED_TRACE(testing::Message()
                     << "slanted " << slanted << ", " << w << "x" << h << ", levels " << levels);
        DenoiseSettings settings;
        settings.levels = levels;
        const Image out = denoise(plane(w, h, slanted, 0.7f), settings);
        const auto [lo, hi] = range_where(out, [](int, int) { return true; });
        EXPECT_NEAR(lo, 0.7f, 0.7f * 1e-6f);
        EXPECT_NEAR(hi, 0.7f, 0.7f * 1e-6f);
      }
    }
  }
}

TEST(Denoise, NoiseVarianceFalls) {
  // Uniform noise of amplitude 1 around 1 (variance 1/12), default settings. Expected about
  // 16x from averaging 4x4 pixels times 20x from the 5x5 Gaussian (sigma 1.5) at 1/4 size.
  // Measured with seed 7: 320x on the fronto-parallel plane, 306x on the slanted one (97x
  // there without the depth-gradient term); over seeds 1-8 the factor ranges 273x-443x, since
  // so smooth a result has few independent samples. The bound sits below that whole range.
  const Scene flat = plane(128, 128, false, 1.0f, 1.0f, 7);
  const Scene slanted = plane(128, 128, true, 1.0f, 1.0f, 7);
  const double before = variance(flat.light);
  const double flat_factor = before / variance(denoise(flat));
  const double slanted_factor = variance(slanted.light) / variance(denoise(slanted));
  std::printf("variance reduction: flat %.0fx, slanted %.0fx\n", flat_factor, slanted_factor);
  EXPECT_NEAR(before, 1.0 / 12, 0.002);
  EXPECT_GT(flat_factor, 250);
  EXPECT_GT(slanted_factor, 250);
}

TEST(Denoise, DepthEdgeDoesNotBleed) {
  // Left: depth 1, light 1; right: depth 10, light 0. At sigma_depth 0.02 the depth term across
  // the edge is exp(-0.5 * 450^2): the two sides must not mix at all, whichever way the edge
  // falls on the 2x2 and 4x4 blocks of the pyramid.
  for (int edge = 29; edge <= 36; ++edge) {
    SCOPED_TRACE(testing::Message() << "edge at x = " << edge);
    Scene s(64, 32);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 64; ++x) {
        if (x < edge)
          s.set(x, y, 1, 1, 0, 0, -1);
        else
          s.set(x, y, 0, 10, 0, 0, -1);
      }
    }
    const Image out = denoise(s);
    const auto [near_lo, near_hi] = range_where(out, [&](int x, int) { return x < edge; });
    const auto [far_lo, far_hi] = range_where(out, [&](int x, int) { return x >= edge; });
    EXPECT_GE(near_lo, 1 - 1e-6f);
    EXPECT_LE(far_hi, 1e-6f);
    EXPECT_GE(far_lo, 0);
  }
}

TEST(Denoise, DiscEdgeDoesNotBleedInAnyDirection) {
  // A disc at depth 1 (light 1) before a wall at depth 10 (light 0), off the pixel grid.
  Scene s(61, 47);
  auto inside = [](int x, int y) {
    return (x - 29.3) * (x - 29.3) + (y - 22.6) * (y - 22.6) < 150;
  };
  for (int y = 0; y < 47; ++y) {
    for (int x = 0; x < 61; ++x) {
      if (inside(x, y))
        s.set(x, y, 1, 1, 0, 0, -1);
      else
        s.set(x, y, 0, 10, 0, 0, -1);
    }
  }
  const Image out = denoise(s);
  EXPECT_GE(range_where(out, inside).first, 1 - 1e-6f);
  EXPECT_LE(range_where(out, [&](int x, int y) { return !inside(x, y); }).second, 1e-6f);
}

TEST(Denoise, NormalCreaseDoesNotBleed) {
  // Two faces at the same depth meeting at 60 degrees: the normal term across the crease is
  // cos(60)^32 = 2.3e-10, so a mix of more than 1e-6 would be a bug.
  const float s30 = 0.5f, c30 = std::sqrt(3.0f) / 2;
  for (int edge = 30; edge <= 33; ++edge) {
    SCOPED_TRACE(testing::Message() << "crease at x = " << edge);
    Scene s(64, 32);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 64; ++x) {
        if (x < edge)
          s.set(x, y, 1, 5, -s30, 0, -c30);
        else
          s.set(x, y, 0, 5, s30, 0, -c30);
      }
    }
    const Image out = denoise(s);
    EXPECT_GE(range_where(out, [&](int x, int) { return x < edge; }).first, 1 - 1e-6f);
    EXPECT_LE(range_where(out, [&](int x, int) { return x >= edge; }).second, 1e-6f);
  }
}

TEST(Denoise, ThinFeatureKeepsItsLight) {
  // A one-pixel pole at depth 1 (light 1) before a wall at depth 10 (light 0) is thinner than a
  // coarse pixel; it must neither vanish into the wall nor light it.
  for (int pole = 20; pole <= 23; ++pole) {
    SCOPED_TRACE(testing::Message() << "pole at x = " << pole);
    Scene s(48, 24);
    for (int y = 0; y < 24; ++y) {
      for (int x = 0; x < 48; ++x) {
        if (x == pole)
          s.set(x, y, 1, 1, 0, 0, -1);
        else
          s.set(x, y, 0, 10, 0, 0, -1);
      }
    }
    const Image out = denoise(s);
    EXPECT_GE(range_where(out, [&](int x, int) { return x == pole; }).first, 1 - 1e-6f);
    EXPECT_LE(range_where(out, [&](int x, int) { return x != pole; }).second, 1e-6f);
  }
}

TEST(Denoise, BackgroundStaysZeroAndDoesNotBleed) {
  // Background carries garbage light (100) in the input: it must come out 0 and not leak into
  // the surface (light 1), whose border pixels must not darken either.
  Scene s(50, 40);
  auto surface = [](int x, int y) { return x >= 13 && x < 38 && y >= 9 && y < 30; };
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 50; ++x) {
      if (surface(x, y))
        s.set(x, y, 1, 3, 0, 0, -1);
      else
        s.set_background(x, y, 100);
    }
  }
  const Image out = denoise(s);
  const auto [surface_lo, surface_hi] = range_where(out, surface);
  EXPECT_NEAR(surface_lo, 1, 1e-6);
  EXPECT_NEAR(surface_hi, 1, 1e-6);
  const auto [bg_lo, bg_hi] = range_where(out, [&](int x, int y) { return !surface(x, y); });
  EXPECT_EQ(bg_lo, 0);
  EXPECT_EQ(bg_hi, 0);
}

// A scene of noise over random depths (some background) and random normals.
Scene random_scene(int w, int h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Scene s(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float value = uniform(rng) * 4;
      const float z = uniform(rng) < 0.1f ? kInf : 1 + uniform(rng) * 0.05f * (1 + x % 7);
      const float nx = uniform(rng) - 0.5f, ny = uniform(rng) - 0.5f;
      s.set(x, y, value, z, nx, ny, -1);
    }
  }
  return s;
}

TEST(Denoise, OddAndTinySizesAreFinite) {
  const std::pair<int, int> sizes[] = {{1, 1}, {2, 2}, {3, 5}, {7, 9}, {1000, 1}, {1, 1000}};
  for (auto [w, h] : sizes) {
    for (int levels = 0; levels <= 4; ++levels) {
      SCOPED_TRACE(testing::Message() << w << "x" << h << ", levels " << levels);
      DenoiseSettings settings;
      settings.levels = levels;
      const Scene s = random_scene(w, h, 3);
      const Image out = denoise(s, settings);
      ASSERT_EQ(out.width(), w);
      ASSERT_EQ(out.height(), h);
      ASSERT_EQ(out.channels(), 3);
      EXPECT_TRUE(all_finite(out));
      const auto [lo, hi] = range_where(out, [](int, int) { return true; });
      EXPECT_GE(lo, 0);
      EXPECT_LE(hi, 4);
      const Image constant = denoise(plane(w, h, true, 0.3f), settings);
      const auto [clo, chi] = range_where(constant, [](int, int) { return true; });
      EXPECT_NEAR(clo, 0.3f, 0.3f * 1e-6f);
      EXPECT_NEAR(chi, 0.3f, 0.3f * 1e-6f);
    }
  }
  EXPECT_EQ(denoise(Scene(0, 0)).width(), 0);
}

TEST(Denoise, SameBitsForOneAndTwoThreads) {
  const Scene s = random_scene(257, 131, 11);
  Image one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = denoise(s);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = denoise(s);
  }
  ASSERT_EQ(one.data().size(), two.data().size());
  EXPECT_EQ(std::memcmp(one.data().data(), two.data().data(), one.bytes()), 0);
}

TEST(Denoise, ExtremeValuesStayFiniteAndInRange) {
  // Light from denormals to 1e30, depths from 1e-4 to 1e9, mixed pixel by pixel: every output is
  // a convex combination of surface inputs, so it stays within their range.
  std::mt19937 rng(5);
  Scene s(67, 45);
  const float lights[] = {1e30f, 1e-38f, 0.0f, 1.0f};
  const float depths[] = {1e-4f, 1e9f, 1.0f, 3e38f, kInf};
  for (int y = 0; y < 45; ++y) {
    for (int x = 0; x < 67; ++x) {
      s.set(x, y, lights[rng() % 4], depths[rng() % 5], 0, 0, -1);
    }
  }
  const Image out = denoise(s);
  EXPECT_TRUE(all_finite(out));
  const auto [lo, hi] = range_where(out, [](int, int) { return true; });
  EXPECT_GE(lo, 0);
  EXPECT_LE(hi, 1e30f);
}

TEST(Denoise, UnusableInputsStayFinite) {
  // NaN and infinite light counts as 0; a NaN, zero or negative depth is background; a zero,
  // NaN or huge normal is unknown or normalised.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Scene s = random_scene(40, 30, 9);
  for (int x = 0; x < 40; x += 3) {
    s.light.at(x % 3, x, 5) = x % 2 ? nan : kInf;
    s.depth.at(0, x, 7) = x % 2 ? nan : (x % 4 ? 0.0f : -1.0f);
    s.normal.at(0, x, 9) = x % 2 ? nan : 3e38f;
    s.normal.at(1, x, 11) = 0;
    s.normal.at(0, x, 11) = 0;
    s.normal.at(2, x, 11) = 0;
  }
  const Image out = denoise(s);
  EXPECT_TRUE(all_finite(out));
  for (int x = 0; x < 40; x += 3) EXPECT_EQ(out.at(0, x, 7), 0);
}

TEST(Denoise, RejectsBadSettingsAndShapes) {
  const Scene s = plane(8, 8, false, 1);
  auto kind_of = [&](const DenoiseSettings& settings, const Image& depth) {
    try {
      denoise_pyramid(s.light, depth, s.normal, settings);
    } catch (const Error& e) {
      return static_cast<int>(e.kind());
    }
    return -1;
  };
  const int usage = static_cast<int>(ErrorKind::kUsage);
  DenoiseSettings bad;
  bad.levels = -1;
  EXPECT_EQ(kind_of(bad, s.depth), usage);
  bad = {};
  bad.sigma_depth = 0;
  EXPECT_EQ(kind_of(bad, s.depth), usage);
  bad = {};
  bad.sigma_spatial = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(kind_of(bad, s.depth), usage);
  bad = {};
  bad.normal_power = -1;
  EXPECT_EQ(kind_of(bad, s.depth), usage);
  EXPECT_EQ(kind_of({}, Image(7, 8, 1)), static_cast<int>(ErrorKind::kInternal));
}

}  // namespace
}  // namespace ssgi::detail
