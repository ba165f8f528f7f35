// The guide's control variate (gi/guide.h) on analytic scenes: planes facing the camera whose
// light is known, a guide without noise, one of zero-mean noise around the truth, and a guide at
// a fraction of the frame's resolution.
#include "gi/guide.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace ssgi::detail {
namespace {

constexpr int kW = 64, kH = 48;
constexpr float kInf = std::numeric_limits<float>::infinity();

// A frame of two planes facing the camera (camera space: +z forward, normals towards the
// camera): the left half at depth 2, the right half at depth 4; at `scale` pixels per trace
// sample its grid is the same scene at 1 / scale of the size.
GBuffer two_planes(int w, int h) {
  GBuffer g;
  g.display_window = g.data_window = {0, 0, w, h};
  g.depth = Image(w, h, 1);
  g.normal = Image(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      g.depth.at(0, x, y) = x < w / 2 ? 2.0f : 4.0f;
      g.normal.at(2, x, y) = -1.0f;
    }
  return g;
}

// The truth on the two planes: a ramp of its own on each, per channel.
float truth(int c, int x, int y, int w) {
  const float u = static_cast<float>(x) / w, v = static_cast<float>(y) / kH;
  return x < w / 2 ? 0.2f + 0.1f * c + 0.3f * u + 0.1f * v : 0.6f - 0.1f * c + 0.2f * v;
}

Image truth_image(int w, int h) {
  Image t(w, h, 3);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) t.at(c, x, y) = truth(c, x, y, w);
  return t;
}

// ssgi's light as the test has it: smooth, at `level` x the truth's mean of each plane.
Image smooth_light(const Image& t, float level) {
  Image l(t.width(), t.height(), 3);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < t.height(); ++y)
      for (int x = 0; x < t.width(); ++x) l.at(c, x, y) = level * t.at(c, x, y);
  return l;
}

GuideFrame guide_of(const Image& light, const Image& depth, int fraction) {
  GuideFrame f;
  f.fraction = fraction;
  f.light = light;
  f.depth = depth;
  return f;
}

double rmse(const Image& a, const Image& b) {
  double sum = 0;
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < a.plane_size(); ++p) {
      const double d = a.plane(c)[p] - b.plane(c)[p];
      sum += d * d;
    }
  return std::sqrt(sum / (3.0 * static_cast<double>(a.plane_size())));
}

double mean(const Image& a) {
  double sum = 0;
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < a.plane_size(); ++p) sum += a.plane(c)[p];
  return sum / (3.0 * static_cast<double>(a.plane_size()));
}

TEST(Guide, AGuideWithoutNoiseGivesItsOwnLight) {
  const GBuffer g = two_planes(kW, kH);
  const Image t = truth_image(kW, kH);
  const Image light = smooth_light(t, 0.5f);
  const GuideOnGrid on_grid = guide_on_grid(g, g, 1, guide_of(t, g.depth, 1), 0.1f);
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < t.plane_size(); ++p) {
      ASSERT_EQ(on_grid.known.plane(c)[p], 1.0f);
      ASSERT_NEAR(on_grid.variance.plane(c)[p], 0.0f, 1e-10f) << "a ramp is not noise";
    }
  GuideReport report;
  const Image out = guided_light(light, on_grid, g.depth, g.normal, 0, DenoiseSettings(), &report);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        ASSERT_NEAR(out.at(c, x, y), t.at(c, x, y), 1e-5f) << c << " " << x << " " << y;
  // Half the light was the residual's.
  EXPECT_NEAR(report.residual_share, 0.5, 1e-4);
  EXPECT_NEAR(report.known_share, 1.0, 1e-9);
}

TEST(Guide, ANoisyGuideAroundTheTruthBeatsBothItAndTheLightAlone) {
  const GBuffer g = two_planes(kW, kH);
  const Image t = truth_image(kW, kH);
  // ssgi 30% too dark; the guide the truth plus zero-mean noise of half the truth's mean.
  const Image light = smooth_light(t, 0.7f);
  Image noisy = t;
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 0.5f * static_cast<float>(mean(t)));
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < noisy.plane_size(); ++p) noisy.plane(c)[p] += noise(rng);
  const GuideOnGrid on_grid = guide_on_grid(g, g, 1, guide_of(noisy, g.depth, 1), 0.1f);
  // The noise estimated from the guide alone: its variance, within 20%.
  double variance = 0;
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < t.plane_size(); ++p) variance += on_grid.variance.plane(c)[p];
  variance /= 3.0 * static_cast<double>(t.plane_size());
  const double sigma = 0.5 * mean(t);
  EXPECT_NEAR(variance / (sigma * sigma), 1.0, 0.2);
  const Image out = guided_light(light, on_grid, g.depth, g.normal, 0, DenoiseSettings());
  const double guided = rmse(out, t), guide = rmse(noisy, t), alone = rmse(light, t);
  EXPECT_LT(guided, 0.25 * guide) << guided << " " << guide;
  EXPECT_LT(guided, 0.25 * alone) << guided << " " << alone;
  // At the truth's level.
  EXPECT_NEAR(mean(out) / mean(t), 1.0, 0.02);
}

TEST(Guide, AFireflyIsSpreadOverItsSurfaceNotKeptNorCut) {
  // ssgi right, the guide right but for one sample 100 times the light (a few-sample render's
  // firefly, a path that found a light by chance): its energy is the guide's, an unbiased
  // estimate's, so it stays in the frame's light, spread over the surface, not left as a spike.
  const GBuffer g = two_planes(kW, kH);
  Image t(kW, kH, 3, 0.5f);
  Image noisy = t;
  const int fx = 10, fy = 20;
  for (int c = 0; c < 3; ++c) noisy.at(c, fx, fy) = 50.0f;
  const GuideOnGrid on_grid = guide_on_grid(g, g, 1, guide_of(noisy, g.depth, 1), 0.1f);
  const Image out = guided_light(t, on_grid, g.depth, g.normal, 0, DenoiseSettings());
  double excess = 0;
  for (std::size_t p = 0; p < out.plane_size(); ++p) excess += out.plane(0)[p] - 0.5;
  EXPECT_LT(out.at(0, fx, fy), 0.5f + 0.05f * 49.5f) << "the spike is kept";
  EXPECT_NEAR(excess / 49.5, 1.0, 0.3) << "the firefly's energy is lost or made";
}

TEST(Guide, WhereTheGuideDoesNotKnowTheLightItIsLeftAsItIs) {
  const GBuffer g = two_planes(kW, kH);
  const Image t = truth_image(kW, kH);
  const Image light = smooth_light(t, 0.5f);
  GuideFrame guide = guide_of(t, g.depth, 1);
  // The green channel unknown everywhere (a pass with albedo, divided by a green albedo of 0).
  guide.known = Image(kW, kH, 3, 1.0f);
  for (std::size_t p = 0; p < guide.known.plane_size(); ++p) guide.known.plane(1)[p] = 0;
  const GuideOnGrid on_grid = guide_on_grid(g, g, 1, guide, 0.1f);
  const Image out = guided_light(light, on_grid, g.depth, g.normal, 0, DenoiseSettings());
  for (std::size_t p = 0; p < t.plane_size(); ++p) {
    ASSERT_EQ(out.plane(1)[p], light.plane(1)[p]);
    ASSERT_NEAR(out.plane(0)[p], t.plane(0)[p], 1e-5f);
    ASSERT_NEAR(out.plane(2)[p], t.plane(2)[p], 1e-5f);
  }
}

TEST(Guide, AGuideAtHalfTheResolutionIsAveragedOverEachSampleOnItsSurface) {
  // The frame at twice the guide's resolution, traced at scale 4: each trace sample's block is
  // 2 x 2 guide pixels.
  const GBuffer frame = two_planes(2 * kW, 2 * kH);
  const GBuffer grid = two_planes(kW / 2, kH / 2);
  Image guide_depth = two_planes(kW, kH).depth;
  Image light(kW, kH, 3);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) light.at(c, x, y) = static_cast<float>(x + 100 * y + c);
  // A pixel of another surface in the first block: left out of its mean.
  guide_depth.at(0, 1, 1) = 10.0f;
  light.at(0, 1, 1) = 1e6f;
  guide_depth.at(0, 0, 2) = kInf;  // no surface
  const GuideOnGrid on_grid = guide_on_grid(frame, grid, 4, guide_of(light, guide_depth, 2), 0.1f);
  // Block (0, 0): guide pixels (0, 0), (1, 0), (0, 1) on its surface.
  EXPECT_FLOAT_EQ(on_grid.mean.at(0, 0, 0), (0.0f + 1.0f + 100.0f) / 3.0f);
  // Block (3, 5): guide pixels x 6..7, y 10..11 all on it.
  EXPECT_FLOAT_EQ(on_grid.mean.at(2, 3, 5), (6 + 7 + 6 + 7 + 2 * 1000 + 2 * 1100) / 4.0f + 2);
  // A ramp has no noise.
  EXPECT_NEAR(on_grid.variance.at(0, 3, 5), 0.0f, 1e-6f);
  EXPECT_EQ(on_grid.known.at(0, 3, 5), 1.0f);
}

TEST(Guide, SamplesWithoutASurfaceAreNotKnown) {
  GBuffer g = two_planes(kW, kH);
  for (int x = 0; x < kW; ++x) g.depth.at(0, x, 0) = kInf;
  const Image t = truth_image(kW, kH);
  const GuideOnGrid on_grid = guide_on_grid(g, g, 1, guide_of(t, g.depth, 1), 0.1f);
  for (int x = 0; x < kW; ++x) EXPECT_EQ(on_grid.known.at(0, x, 0), 0.0f);
  EXPECT_EQ(on_grid.known.at(0, 5, 5), 1.0f);
}

}  // namespace
}  // namespace ssgi::detail
