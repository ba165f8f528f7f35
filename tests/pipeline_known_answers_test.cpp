// The GI pipeline on fixtures with known answers (testdata/README.md describes each): the
// furnace, bounces, a lone plane under its environment, symmetry, the same bits for any thread
// count, crops and coarse trace grids.
#include <OpenImageIO/imageio.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "pipeline_support.h"

namespace ssgi::pipeline_test {
namespace {

void expect_all_finite(const Image& img) {
  for (float v : img.data()) ASSERT_TRUE(std::isfinite(v));
}

// A camera inside a closed box whose every surface reflects L = 0.5, misses returning L too:
// every ray, hit or miss, brings L, so one bounce gives exactly L (to 1%).
TEST(Pipeline, FurnaceOneBounceIsL) {
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    GiSettings s;
    s.tracer = tracer;
    s.bounces = 1;
    s.miss = MissMode::kEnvironment;
    s.env_color = {0.5f, 0.5f, 0.5f};
    const Frame f = load("furnace/furnace.0001.exr", s);
    const FrameResult r = run(f, s);
    for (int c = 0; c < 3; ++c)
      for (std::size_t p = 0; p < r.indirect.plane_size(); ++p)
        ASSERT_NEAR(r.indirect.plane(c)[p], 0.5f, 0.005f);
  }
}

// The furnace with a patch of its wall an emitter: no diffuse albedo, the same light leaving it.
// Every ray still brings L, but the patch reflects no diffuse light: its indirect is 0, as in the
// renderers' diffuse passes (Cycles' DiffInd is 0 on a screen or a lamp), the rest L.
TEST(Pipeline, ASurfaceWithoutDiffuseAlbedoGetsNoIndirectLight) {
  GiSettings s;
  s.bounces = 1;
  s.miss = MissMode::kEnvironment;
  s.env_color = {0.5f, 0.5f, 0.5f};
  Frame f = load("furnace/furnace.0001.exr", s);
  GBuffer& g = f.g;
  auto patch = [&](int x, int y) { return x >= 10 && x < 20 && y >= 10 && y < 20; };
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      if (patch(x, y))
        for (int c = 0; c < 3; ++c) g.albedo.at(c, x, y) = 0.0f;
  const FrameResult r = run(f, s);
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        if (patch(x, y)) {
          ASSERT_EQ(r.indirect.at(c, x, y), 0.0f) << x << "," << y;
          ASSERT_EQ(r.gi.at(c, x, y), 0.0f);
        } else {
          ASSERT_NEAR(r.indirect.at(c, x, y), 0.5f, 0.005f) << x << "," << y;
        }
      }
}

// With misses estimated from the frame every ray brings the frame's mean light, so N bounces
// over albedo 0.5 give the geometric series 0.5 (1 + 0.5 + ... + 0.5^(N-1)) = 1 - 0.5^N.
TEST(Pipeline, FurnaceBouncesFollowTheGeometricSeries) {
  for (Tracer tracer : kTracers)
    for (int bounces : {2, 4, 8}) {
      GiSettings s;
      s.tracer = tracer;
      s.bounces = bounces;
      s.miss = MissMode::kFrame;
      const Frame f = load("furnace/furnace.0001.exr", s);
      const FrameResult r = run(f, s);
      const float expected = 1.0f - std::pow(0.5f, static_cast<float>(bounces));
      for (std::size_t p = 0; p < r.indirect.plane_size(); ++p)
        ASSERT_NEAR(r.indirect.plane(0)[p], expected, 0.01f * expected) << "bounces " << bounces;
    }
}

// A lone plane cannot see itself: under a black environment every ray misses and indirect is
// exactly 0; under a constant environment C it is C (to float rounding of the denoiser).
TEST(Pipeline, LonePlaneSeesOnlyTheEnvironment) {
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    GiSettings s;
    s.tracer = tracer;
    s.miss = MissMode::kEnvironment;
    s.rays = 16;
    const Frame f = load("plane/plane.0001.exr", s);
    const FrameResult black = run(f, s);
    for (float v : black.indirect.data()) ASSERT_EQ(v, 0.0f);

    s.env_color = {0.2f, 0.4f, 0.8f};
    const FrameResult lit = run(f, s);
    for (int y = 0; y < f.g.height(); ++y)
      for (int x = 0; x < f.g.width(); ++x) {
        if (!f.g.is_surface(x, y)) continue;
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(lit.indirect.at(c, x, y), s.env_color[c], 1e-5f * s.env_color[c]);
      }
  }
}

// Indirect light is a mean of what rays bring, and the denoiser a convex combination, so one
// bounce never exceeds the brightest light in the frame or the environment; also where the
// input has NaN and infinite samples (read as 0, not as huge light).
TEST(Pipeline, OneBounceNeverExceedsTheBrightestSource) {
  for (const char* pattern : {"sample/sample.####.exr", "bad/nan.0001.exr"})
    for (MissMode miss : {MissMode::kEnvironment, MissMode::kFrame, MissMode::kAuto})
      for (Tracer tracer : kTracers) {
        SCOPED_TRACE(pattern);
        GiSettings s;
        s.tracer = tracer;
        s.bounces = 1;
        s.miss = miss;
        s.env_color = {0.3f, 0.3f, 0.3f};
        const Frame f = load(pattern, s);
        const FrameResult r = run(f, s);
        for (int c = 0; c < 3; ++c) {
          float brightest = s.env_color[c];
          for (std::size_t p = 0; p < f.g.direct.plane_size(); ++p)
            if (std::isfinite(f.g.depth.plane(0)[p]))
              brightest = std::max(brightest, f.g.direct.plane(c)[p]);
          for (float v : std::vector<float>(r.indirect.plane(c),
                                            r.indirect.plane(c) + r.indirect.plane_size()))
            ASSERT_LE(v, brightest * (1 + 1e-6f));
        }
      }
}

// A scene mirror-symmetric about the image's centre column gives a mirror-symmetric result up
// to the noise, which is not symmetric (IGN is not): the mean difference between a pixel and its
// mirror stays a few percent of the mean.
TEST(Pipeline, MirrorSymmetricSceneGivesSymmetricResult) {
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    GiSettings s;
    s.tracer = tracer;
    s.slices = 16;
    s.rays = 32;
    const Frame f = load("symmetric/symmetric.0001.exr", s);
    const FrameResult r = run(f, s);
    const int w = f.g.width(), h = f.g.height();
    double diff = 0, sum = 0;
    for (int c = 0; c < 3; ++c)
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          diff += std::fabs(r.indirect.at(c, x, y) - r.indirect.at(c, w - 1 - x, y));
          sum += r.indirect.at(c, x, y);
        }
    ASSERT_GT(sum, 0);
    EXPECT_LT(diff / sum, 0.05);
  }
}

// The same bits for 1 and 2 threads, and run to run.
TEST(Pipeline, SameBitsForAnyThreadCount) {
  GiSettings s;
  const Frame f = load("sample/sample.####.exr", s);
  FrameResult one, two, again;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = run(f, s);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = run(f, s);
    again = run(f, s);
  }
  EXPECT_EQ(one.indirect.data(), two.indirect.data());
  EXPECT_EQ(one.composite.data(), two.composite.data());
  EXPECT_EQ(two.composite.data(), again.composite.data());
}

// No NaN or Inf in any output, on every fixture, including NaN/inf-riddled inputs.
TEST(Pipeline, OutputsAreFiniteOnEveryFixture) {
  for (const char* pattern :
       {"sample/sample.####.exr", "furnace/furnace.0001.exr", "plane/plane.0001.exr",
        "symmetric/symmetric.0001.exr", "moving/moving.####.exr", "overscan/overscan.0001.exr",
        "crop/crop.0001.exr", "bad/nan.0001.exr"}) {
    for (MissMode miss : {MissMode::kAuto, MissMode::kExtend})
      for (Tracer tracer : kTracers) {
        if (tracer == Tracer::kSlices && miss == MissMode::kExtend) continue;  // march only
        GiSettings s;
        s.tracer = tracer;
        s.rays = 4;
        s.miss = miss;
        const Frame f = load(pattern, s);
        const FrameResult r = run(f, s);
        SCOPED_TRACE(pattern);
        expect_all_finite(r.indirect);
        expect_all_finite(r.gi);
        expect_all_finite(r.composite);
      }
  }
}

// Noise is keyed to display-window pixels: a crop of the frame gives the same undenoised
// indirect light where it overlaps the full frame, as long as rays stay inside both.
TEST(Pipeline, CropKeepsTheSameNoise) {
  GiSettings s;
  s.denoise = DenoiseMode::kNone;
  s.miss = MissMode::kEnvironment;
  s.bounces = 1;
  s.max_distance = 0.05;  // short rays: the crop's edge does not cut them
  const Frame full = load("sample/sample.####.exr", s);
  const Frame crop = load("crop/crop.0001.exr", s);
  const FrameResult a = run(full, s), b = run(crop, s);
  const Box2i& cw = crop.g.data_window;
  int compared = 0;
  for (int y = 2; y < cw.height() - 2; ++y)
    for (int x = 2; x < cw.width() - 2; ++x) {
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(b.indirect.at(c, x, y), a.indirect.at(c, x + cw.x0, y + cw.y0));
      ++compared;
    }
  EXPECT_GT(compared, 1000);
}

// Writes a 2:1 lat-long map that is `upper` above the horizon (OpenEXR's +Y up) and `lower`
// below it.
std::string write_two_tone_env(const std::string& name, float upper, float lower) {
  const int w = 64, h = 32;
  std::vector<float> pixels(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        pixels[(static_cast<std::size_t>(y) * w + x) * 3 + c] = y < h / 2 ? upper : lower;
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("ssgi_pipeline_test_" + name + "." + std::to_string(getpid()) + ".exr"))
          .string();
  auto out = OIIO::ImageOutput::create(path);
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
  EXPECT_TRUE(out && out->open(path, spec) &&
              out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) && out->close());
  return path;
}

// The lone plane (world +Z up, Blender's convention) under a map bright above OpenEXR's
// horizon: with --env-up z the plane's hemisphere is the bright half, so indirect = 1; with the
// map's own +Y up, world +Z is horizontal in the map, half the cosine-weighted hemisphere is
// bright, so indirect = 0.5 up to the sampling noise, which the denoiser averages down.
TEST(Pipeline, EnvironmentMapFollowsItsUpAxis) {
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    const std::string env = write_two_tone_env("two_tone", 1.0f, 0.0f);
    GiSettings s;
    s.tracer = tracer;
    s.miss = MissMode::kEnvironment;
    s.env_map = env;
    s.rays = 64;
    s.bounces = 1;
    const Frame f = load("plane/plane.0001.exr", s);
    for (char up : {'z', 'y'}) {
      s.env_up = up;
      const FrameResult r = run(f, s);
      double sum = 0;
      int n = 0;
      for (int y = 0; y < f.g.height(); ++y)
        for (int x = 0; x < f.g.width(); ++x)
          if (f.g.is_surface(x, y)) {
            sum += r.indirect.at(0, x, y);
            ++n;
          }
      ASSERT_GT(n, 0);
      EXPECT_NEAR(sum / n, up == 'z' ? 1.0 : 0.5, up == 'z' ? 0.01 : 0.03) << "up " << up;
    }
    std::filesystem::remove(env);
  }
}

// The slice tracer at trace scales 2, 4 and 8 (the default at 1080p and above; the fixtures
// are small enough to be traced at every pixel by default): the known answers still hold. A
// plane stays a plane on the coarser grid (each block holds its traced pixel's plane at the
// block's centre), the furnace stays exact (weights sum to 1), odd sizes leave partial blocks
// at the edges, and threads do not change the bits.
TEST(Pipeline, CoarseTraceGridsKeepTheKnownAnswers) {
  for (int scale : {2, 4, 8}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    GiSettings s;
    s.trace_scale = scale;
    s.miss = MissMode::kEnvironment;
    s.bounces = 1;
    const Frame plane = load("plane/plane.0001.exr", s);
    const FrameResult black = run(plane, s);
    for (float v : black.indirect.data()) ASSERT_EQ(v, 0.0f);
    s.env_color = {0.5f, 0.5f, 0.5f};
    const Frame furnace = load("furnace/furnace.0001.exr", s);
    const FrameResult r = run(furnace, s);
    for (std::size_t p = 0; p < r.indirect.plane_size(); ++p)
      ASSERT_NEAR(r.indirect.plane(0)[p], 0.5f, 0.005f);
    // Every fixture, odd crops among them: finite, and the same for 1 and 2 threads.
    for (const char* pattern :
         {"sample/sample.####.exr", "crop/crop.0001.exr", "overscan/overscan.0001.exr",
          "bad/nan.0001.exr", "symmetric/symmetric.0001.exr"}) {
      SCOPED_TRACE(pattern);
      GiSettings d;
      d.trace_scale = scale;
      const Frame f = load(pattern, d);
      FrameResult one, two;
      {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = run(f, d);
      }
      {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        two = run(f, d);
      }
      expect_all_finite(one.indirect);
      EXPECT_EQ(one.indirect.data(), two.indirect.data());
    }
  }
}

// The sample frame traced at scale 2 sees about the light it sees at every pixel: the coarse
// grid changes the sampling, not the answer (mean indirect within 5%, and non-zero).
TEST(Pipeline, CoarseTraceGridGivesTheFullGridsLight) {
  GiSettings fine;
  fine.trace_scale = 1;
  const Frame f = load("sample/sample.0001.exr", fine);
  auto mean = [&](const FrameResult& r) {
    double sum = 0;
    for (float v : r.indirect.data()) sum += v;
    return sum / static_cast<double>(r.indirect.data().size());
  };
  const double full = mean(run(f, fine));
  GiSettings coarse = fine;
  coarse.trace_scale = 2;
  const double half = mean(run(f, coarse));
  ASSERT_GT(full, 0.01);
  EXPECT_NEAR(half, full, 0.05 * full);
}

}  // namespace
}  // namespace ssgi::pipeline_test
