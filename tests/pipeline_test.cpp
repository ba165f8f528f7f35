// The GI pipeline on scenes with known answers (testdata/README.md describes each fixture).
#include "ssgi/pipeline.h"

#include <OpenImageIO/imageio.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "directions.h"
#include "fixture_frame.h"
#include "gtest/gtest.h"
#include "input_frame.h"
#include "misses.h"
#include "ssgi/color.h"
#include "ssgi/io.h"
#include "surface_model.h"

namespace ssgi {
namespace {

using Frame = test_fixtures::FixtureFrame;

Frame load(const std::string& pattern, const GiSettings& settings) {
  return test_fixtures::load_fixture(pattern, settings);
}

FrameResult run(const Frame& f, const GiSettings& settings) {
  const Pipeline pipeline(f.seq, settings);
  return pipeline.composite(f.g, pipeline.indirect_light(f.g));
}

// Every tracer follows the same surface model and miss rules: the known answers hold for each.
const Tracer kTracers[] = {Tracer::kSlices, Tracer::kScreenSpace};
const char* tracer_name(Tracer t) { return t == Tracer::kSlices ? "slices" : "march"; }

void expect_all_finite(const Image& img) {
  for (float v : img.data()) ASSERT_TRUE(std::isfinite(v));
}

// A camera inside a closed box whose every surface reflects L = 0.5, misses returning L too:
// every ray, hit or miss, brings L, so one bounce gives exactly L (the 1% bound).
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
      (std::filesystem::temp_directory_path() / ("ssgi_pipeline_test_" + name + ".exr")).string();
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

// A known answer that only hits can give: a right-angled groove seen head-on through a narrow
// lens, its crease along the image's middle row. The upper face reflects 1, the lower 0; under a
// black environment a point of the lower face at distance d from the crease gets the view
// factor of the upper face, which in the groove's cross-section is (1 - d / sqrt(d^2 + L^2)) / 2
// for an upper face of length L (Hottel's crossed strings: (1 + cos 90 deg) / 2 as d -> 0). The
// rays that run along the groove and leave the frame sideways are the rest of the tolerance.
// A tracer that missed every ray would give 0.
// A right-angled groove seen head-on: its upper face lit (direct 1, albedo 1), its lower face
// dark, the crease across the middle of the frame at depth 10; misses go to the environment.
struct Groove {
  Frame f;
  double length;  // the upper face's length in the cross-section, crease to the frame's top
  // The view factor of the whole upper face from pixel (x, y) of the lower face.
  double view_factor(int x, int y) const {
    const Imath::V3d p = f.g.camera.unproject(x + 0.5, y + 0.5, f.g.depth.at(0, x, y));
    const double d = std::hypot(p.y, p.z - 10.0);
    return 0.5 * (1 - d / std::hypot(d, length));
  }
};

Groove make_groove(const GiSettings& base) {
  Groove groove{load("plane/plane.0001.exr", base), 0};
  GBuffer& g = groove.f.g;
  const int w = g.width(), h = g.height();
  g.camera = camera_from_fov(10.0, g.display_window);
  const Camera& cam = g.camera;
  const double z0 = 10.0;
  g.depth = Image(w, h, 1);
  g.normal = Image(w, h, 3);
  g.albedo = Image(w, h, 3, 1.0f);
  g.direct = Image(w, h, 3);
  if (!g.emission.empty()) g.emission = Image(w, h, 3);
  const double r = std::sqrt(0.5);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double yn = (cam.cy - (y + 0.5)) / cam.fy;  // camera y / z of the pixel's ray
      g.depth.at(0, x, y) = static_cast<float>(z0 / (1.0 + std::fabs(yn)));
      const bool upper = yn > 0;
      g.normal.at(1, x, y) = static_cast<float>(upper ? -r : r);
      g.normal.at(2, x, y) = static_cast<float>(-r);
      for (int c = 0; c < 3; ++c) g.direct.at(c, x, y) = upper ? 1.0f : 0.0f;
    }
  const double yn_top = cam.cy / cam.fy, z_top = z0 / (1 + yn_top);
  groove.length = std::hypot(yn_top * z_top, z0 - z_top);
  return groove;
}

// One bounce, no denoiser or temporal stage, misses to the environment; converged tracers.
GiSettings groove_settings(Tracer tracer) {
  GiSettings s;
  s.miss = MissMode::kEnvironment;
  s.bounces = 1;
  s.denoise = DenoiseMode::kNone;
  s.temporal = TemporalMode::kNone;
  s.tracer = tracer;
  s.trace_scale = 1;
  s.slices = 16;
  s.rays = 64;
  s.max_steps = 64;
  return s;
}

TEST(Pipeline, GrooveGivesTheViewFactorOfItsLitFace) {
  const Groove groove = make_groove(groove_settings(Tracer::kSlices));
  const GBuffer& g = groove.f.g;
  ASSERT_EQ(g.data_window, g.display_window);
  const int w = g.width(), h = g.height();
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    const Pipeline pipeline(groove.f.seq, groove_settings(tracer));
    const Image indirect = pipeline.indirect_light(g);
    double ratio = 0;
    int n = 0;
    for (int y = h / 2; y < h / 2 + 4; ++y)
      for (int x = w / 4; x < 3 * w / 4; ++x) {
        const double expected = groove.view_factor(x, y);
        ASSERT_GT(expected, 0.4);
        ratio += indirect.at(0, x, y) / expected;
        ++n;
      }
    std::printf("%s: indirect / view factor %.4f over %d pixels\n", tracer_name(tracer), ratio / n,
                n);
    EXPECT_NEAR(ratio / n, 1.0, 0.05);
  }
}

// Coverage: the lower face's light comes through its rays to the lit face (view factor F) and
// through the misses to an environment of 0.5 (the rest of its hemisphere), so that the traced
// share is F / (F + 0.5 (1 - F)); the lit face's rays meet only the dark face, so that all its
// light is the environment's (0). With a black environment the lit face gathers nothing, and
// its coverage is the share of its hemisphere that met the dark face.
TEST(Pipeline, CoverageIsTheShareOfTheLightTheTracedRaysBrought) {
  const Groove groove = make_groove(groove_settings(Tracer::kSlices));
  const GBuffer& g = groove.f.g;
  const int w = g.width(), h = g.height();
  // Both tracers from every pixel, and the slices from a trace grid of 2 x 2 blocks (its
  // coverage carried to the frame's pixels).
  for (auto [tracer, scale] : {std::pair{Tracer::kSlices, 1}, std::pair{Tracer::kScreenSpace, 1},
                               std::pair{Tracer::kSlices, 2}}) {
    SCOPED_TRACE(std::string(tracer_name(tracer)) + " at trace scale " + std::to_string(scale));
    for (float env : {0.5f, 0.0f}) {
      GiSettings s = groove_settings(tracer);
      s.trace_scale = scale;
      s.env_color = {env, env, env};
      const Pipeline pipeline(groove.f.seq, s);
      Image coverage;
      pipeline.indirect_light(g, &coverage);
      const FrameResult result = pipeline.composite(g, pipeline.indirect_light(g), coverage);
      ASSERT_EQ(result.coverage.channels(), 1);
      double lower = 0, upper = 0;
      int n = 0;
      for (int y = h / 2; y < h / 2 + 4; ++y)
        for (int x = w / 4; x < 3 * w / 4; ++x) {
          const double f = groove.view_factor(x, y);
          const double expected = env > 0 ? f / (f + env * (1 - f)) : 1.0;
          lower += result.coverage.at(0, x, y) / expected;
          // The lit face's mirror pixel sees the dark face as the dark face sees it.
          upper += result.coverage.at(0, x, h - 1 - y) - (env > 0 ? 0.0 : f);
          ++n;
        }
      std::printf(
          "%s, scale %d, env %.1f: coverage / expected %.4f (dark face), - expected %.4f "
          "(lit)\n",
          tracer_name(tracer), scale, env, lower / n, upper / n);
      EXPECT_NEAR(lower / n, 1.0, 0.05);
      EXPECT_NEAR(upper / n, 0.0, 0.03);
    }
  }
}

// Multiframe (lib/src/gi/multiframe.h): a lit face that only a neighbouring frame shows. Frame 2
// sees the groove head-on, its lit upper face from the crease to the frame's top; frame 1 is
// the same groove from a camera moved by (0.4, 0, -0.5) and pitched 6 degrees down (half its
// vertical field of view is 3.75), so that it shows the dark lower face alone: the rays its pixels
// send to the lit face leave its frame, and with black misses it gets no light at all. Continued in
// frame 2's depth buffer they find the lit face where frame 2 shows it: frame 1's light is the
// share of each pixel's cosine-weighted hemisphere whose rays meet the lit face at a point inside
// frame 2's view, integrated here by brute force over directions.
TEST(Pipeline, MultiframeFindsALitFaceOnlyANeighbourShows) {
  GiSettings s = groove_settings(Tracer::kSlices);
  s.temporal = TemporalMode::kWindow;
  s.multiframe = kMultiframeWindow;
  s.slices = 64;  // two continued rays a slice: many slices, so that a row's mean is converged
  Groove groove = make_groove(s);
  GBuffer& b = groove.f.g;  // camera space is world space
  b.frame = 2;
  b.camera.has_world_transform = true;
  GBuffer a = b;
  a.frame = 1;
  const double pitch = 6.0 * M_PI / 180.0;
  // Camera 1's axes in world space; world_to_camera's columns (row-vector convention).
  const Imath::V3d right{1, 0, 0}, up{0, std::cos(pitch), std::sin(pitch)},
      forward{0, -std::sin(pitch), std::cos(pitch)};
  const Imath::V3d axes[3] = {right, up, forward};
  const Imath::V3d centre{0.4, 0.0, -0.5};
  for (int j = 0; j < 3; ++j) {
    a.camera.world_to_camera[0][j] = axes[j].x;
    a.camera.world_to_camera[1][j] = axes[j].y;
    a.camera.world_to_camera[2][j] = axes[j].z;
    a.camera.world_to_camera[3][j] =
        -(centre.x * axes[j].x + centre.y * axes[j].y + centre.z * axes[j].z);
  }
  const Camera& cam = a.camera;
  const int w = a.width(), h = a.height();
  const double r = std::sqrt(0.5);
  std::vector<Imath::V3d> point(static_cast<std::size_t>(w) * h, Imath::V3d(0));  // world space
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double c[3] = {(x + 0.5 - cam.cx) / cam.fx, (cam.cy - (y + 0.5)) / cam.fy, 1.0};
      const Imath::V3d d{c[0] * right.x + c[1] * up.x + c[2] * forward.x,
                         c[0] * right.y + c[1] * up.y + c[2] * forward.y,
                         c[0] * right.z + c[1] * up.z + c[2] * forward.z};
      // The lower face: z - y = 10, y < 0.
      const double t = (10.0 - centre.z + centre.y) / (d.z - d.y);
      const Imath::V3d p{centre.x + t * d.x, centre.y + t * d.y, centre.z + t * d.z};
      ASSERT_LT(p.y, 0.0);
      point[static_cast<std::size_t>(y) * w + x] = p;
      a.depth.at(0, x, y) = static_cast<float>(t);  // camera 1's z of the point
      const Imath::V3d n{0, r, -r};
      for (int k = 0; k < 3; ++k)
        a.normal.at(k, x, y) =
            static_cast<float>(n.x * axes[k].x + n.y * axes[k].y + n.z * axes[k].z);
      for (int k = 0; k < 3; ++k) a.direct.at(k, x, y) = 0.0f;
    }
  SequenceInfo seq = groove.f.seq;
  seq.frames = seq.frames_on_disk = {1, 2};
  const Pipeline pipeline(seq, s);
  ASSERT_EQ(pipeline.plan().multiframe, s.temporal_radius);
  const Pipeline::TracedLight ta = pipeline.trace_light(a), tb = pipeline.trace_light(b);
  for (float v : ta.light.data()) ASSERT_EQ(v, 0.0f);  // alone it sees no light
  Image light, coverage;
  ASSERT_TRUE(pipeline.continue_light(a, {&ta, &tb}, 0, &light, &coverage));

  // The expected share, over a grid of cosine-weighted directions.
  const Camera& camera_b = b.camera;
  auto expected = [&](const Imath::V3d& p) {
    constexpr int kSide = 200;
    int lit = 0;
    for (int i = 0; i < kSide; ++i)
      for (int j = 0; j < kSide; ++j) {
        const Imath::V3f d =
            detail::cosine_hemisphere({0.0f, static_cast<float>(r), static_cast<float>(-r)},
                                      (i + 0.5f) / kSide, (j + 0.5f) / kSide);
        const double t = (10.0 - p.z - p.y) / (d.z + d.y);  // the upper face: z + y = 10
        if (!(t > 0)) continue;
        const Imath::V3d q{p.x + t * d.x, p.y + t * d.y, p.z + t * d.z};
        double qx, qy;
        camera_b.project(q, &qx, &qy);
        if (q.y > 0 && q.z > 0 && qx >= 0 && qx <= w && qy >= 0 && qy <= h) ++lit;
      }
    return static_cast<double>(lit) / (kSide * kSide);
  };
  // The rows nearest the crease, where the lit face fills much of the hemisphere: each row's
  // mean (a pixel's few continued rays a slice are noisy) and all of them.
  double sum_got = 0, sum_expected = 0;
  for (int y = 0; y < 6; ++y) {
    double row_got = 0, row_expected = 0;
    for (int x = w / 4; x < 3 * w / 4; x += 2) {
      const double e = expected(point[static_cast<std::size_t>(y) * w + x]);
      ASSERT_GT(e, 0.05);
      row_expected += e;
      row_got += light.at(0, x, y);
      EXPECT_GT(coverage.at(0, x, y), 0.99f);  // all its light was traced, in frame 2
    }
    EXPECT_NEAR(row_got / row_expected, 1.0, 0.15) << "row " << y;
    sum_got += row_got;
    sum_expected += row_expected;
  }
  std::printf("frame 1 with its rays continued in frame 2: %.4f, expected %.4f\n", sum_got,
              sum_expected);
  EXPECT_NEAR(sum_got / sum_expected, 1.0, 0.08);

  // What is left to the miss model (the window levels it): with --miss frame every miss is the
  // cube's and its shares sum to its weight, so frame 1's shares fall by the lit face's share
  // of its hemisphere, the rays found there, and nowhere rise.
  {
    GiSettings framed = s;
    framed.miss = MissMode::kFrame;
    const Pipeline p(seq, framed);
    const Pipeline::TracedLight fa = p.trace_light(a), fb = p.trace_light(b);
    ASSERT_EQ(fa.miss_shares.channels(), 3);
    Image continued, continued_coverage, left;
    ASSERT_TRUE(p.continue_light(a, {&fa, &fb}, 0, &continued, &continued_coverage, &left));
    ASSERT_EQ(left.channels(), 3);
    for (int g = 0; g < 3; ++g)
      for (std::size_t i = 0; i < left.plane_size(); ++i)
        ASSERT_LE(left.plane(g)[i], fa.miss_shares.plane(g)[i] + 1e-6f) << g << " at " << i;
    double found = 0, lit = 0;
    for (int y = 0; y < 6; ++y)
      for (int x = w / 4; x < 3 * w / 4; x += 2) {
        for (int g = 0; g < 3; ++g) found += fa.miss_shares.at(g, x, y) - left.at(g, x, y);
        lit += expected(point[static_cast<std::size_t>(y) * w + x]);
      }
    EXPECT_NEAR(found / lit, 1.0, 0.08);
  }

  // A neighbour with the frame's own camera adds nothing.
  GBuffer still = b;
  still.frame = 1;
  const Pipeline::TracedLight ts = pipeline.trace_light(still);
  EXPECT_FALSE(pipeline.continue_light(still, {&ts, &tb}, 0, &light, &coverage));
}

// Settings that take the tracers to their converged answer on a small analytic scene: every
// pixel traced, many slices, rays and samples, no denoise, no temporal stage.
GiSettings converged_settings() {
  GiSettings s;
  s.denoise = DenoiseMode::kNone;
  s.temporal = TemporalMode::kNone;
  s.trace_scale = 1;
  s.slices = 16;
  s.rays = 64;
  s.max_steps = 64;
  return s;
}

// The plane fixture's frame emptied for an analytic scene drawn into it: a centred camera of
// `hfov` degrees (no world transform: camera space is world space), depth `depth`, no normals,
// albedo 0.5, no light.
Frame blank_scene(const GiSettings& settings, double hfov, float depth) {
  Frame f = load("plane/plane.0001.exr", settings);
  GBuffer& g = f.g;
  const int w = g.width(), h = g.height();
  g.camera = camera_from_fov(hfov, g.display_window);
  g.depth = Image(w, h, 1, depth);
  g.normal = Image(w, h, 3);
  g.albedo = Image(w, h, 3, 0.5f);
  g.direct = Image(w, h, 3);
  if (!g.emission.empty()) g.emission = Image(w, h, 3);
  return f;
}

// A lit panel in front of a backdrop, over a floor: the backdrop sees the panel's unlit back,
// so the light of the panel's front never reaches it (surface_model.h), while the floor in front
// of the panel gets it; from the second bounce the back brings the panel's albedo x its own
// indirect light. Camera space is world space; misses bring the environment C.
TEST(Pipeline, AHitFromBehindBringsTheBackNotTheLitFront) {
  GiSettings base = converged_settings();
  base.miss = MissMode::kEnvironment;
  base.env_color = {0.5f, 0.5f, 0.5f};
  Frame f = blank_scene(base, 60.0, 0.0f);
  GBuffer& g = f.g;
  const int w = g.width(), h = g.height();
  const Camera& cam = g.camera;
  enum Surface { kFloor, kPanel, kBackdrop };
  std::vector<Surface> what(static_cast<std::size_t>(w) * h);
  const double floor_y = -1.5, panel_z = 6, panel_top = 0.3, panel_x = 2, backdrop_z = 10;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double rx = (x + 0.5 - cam.cx) / cam.fx, ry = (cam.cy - (y + 0.5)) / cam.fy;
      double z = backdrop_z;
      Surface s = kBackdrop;
      if (std::fabs(rx * panel_z) < panel_x && ry * panel_z < panel_top && ry * panel_z > floor_y)
        z = panel_z, s = kPanel;
      if (ry < 0 && floor_y / ry < z) z = floor_y / ry, s = kFloor;
      g.depth.at(0, x, y) = static_cast<float>(z);
      g.normal.at(s == kFloor ? 1 : 2, x, y) = s == kFloor ? 1.0f : -1.0f;
      what[static_cast<std::size_t>(y) * w + x] = s;
    }
  auto with_panel = [&](float direct, float albedo) {
    GBuffer out = g;
    for (std::size_t p = 0; p < what.size(); ++p)
      if (what[p] == kPanel)
        for (int c = 0; c < 3; ++c)
          out.direct.plane(c)[p] = direct, out.albedo.plane(c)[p] = albedo;
    return out;
  };
  const GBuffer dark = with_panel(0, 0.5f), lit = with_panel(1, 0.5f), black = with_panel(0, 0);
  // The backdrop just above the panel's top edge, and the floor in front of it.
  std::vector<std::size_t> backdrop, floor;
  for (int y = 0; y < h; ++y)
    for (int x = w / 3; x < 2 * w / 3; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      if (what[p] == kBackdrop && y + 3 < h && what[p + 3 * w] == kPanel) backdrop.push_back(p);
      if (what[p] == kFloor && g.depth.plane(0)[p] < panel_z - 1) floor.push_back(p);
    }
  ASSERT_GE(backdrop.size(), 20u);
  ASSERT_GE(floor.size(), 20u);

  for (Tracer tracer : {Tracer::kSlices, Tracer::kScreenSpace, Tracer::kReference}) {
    SCOPED_TRACE(tracer == Tracer::kReference ? "reference" : tracer_name(tracer));
    GiSettings s = base;
    s.tracer = tracer;
    s.bounces = 1;
    const Pipeline one(f.seq, s);
    const Image a = one.indirect_light(dark), b = one.indirect_light(lit);
    for (std::size_t p : backdrop) ASSERT_EQ(a.plane(0)[p], b.plane(0)[p]);
    double gain = 0;
    for (std::size_t p : floor) gain += (b.plane(0)[p] - a.plane(0)[p]) / floor.size();
    EXPECT_GT(gain, 0.02);
    s.bounces = 2;
    const Pipeline two(f.seq, s);
    const Image grey = two.indirect_light(dark), none = two.indirect_light(black);
    double back = 0;
    for (std::size_t p : backdrop) back += (grey.plane(0)[p] - none.plane(0)[p]) / backdrop.size();
    std::printf("%s: floor gains %.4f from the lit front; the backdrop %.4f from the back\n",
                tracer == Tracer::kReference ? "reference" : tracer_name(tracer), gain, back);
    EXPECT_GT(back, 0.005);
  }
}

// Read through an ACEScg -> lin_rec709 transform, the colour passes change and the data passes
// (depth, normals, motion) keep every bit.
TEST(Pipeline, ColourTransformsTouchLightAndAlbedoOnly) {
  InputOptions in;
  in.pattern = std::string(SSGI_TESTDATA_DIR) + "/moving/moving.0002.exr";
  const SequenceInfo seq = open_sequence(in);
  GiSettings s;
  const RoleMask roles = make_plan(seq, s).roles;
  ASSERT_TRUE(roles & role_bit(Role::kMotion));
  ColorSettings c;
  c.config = std::string(SSGI_TESTDATA_DIR) + "/ocio/config.ocio";
  c.input = "ACEScg";
  const ColorManagement color(c);
  EXPECT_EQ(color.working_space(), "lin_rec709");
  const GBuffer plain = read_gbuffer(seq, 2, roles, in);
  const GBuffer converted = read_gbuffer(seq, 2, roles, in, &color);
  for (const auto& [name, a, b] :
       {std::tuple{"depth", &plain.depth, &converted.depth},
        std::tuple{"normal", &plain.normal, &converted.normal},
        std::tuple{"motion_prev", &plain.motion_prev, &converted.motion_prev}}) {
    ASSERT_FALSE(a->empty()) << name;
    ASSERT_EQ(a->data().size(), b->data().size()) << name;
    EXPECT_EQ(std::memcmp(a->data().data(), b->data().data(), a->bytes()), 0) << name;
  }
  // ACEScg (1, 0, 0) is lin_rec709 (1.705, -0.130, -0.024): red albedo gets redder.
  double changed = 0;
  for (std::size_t i = 0; i < plain.albedo.data().size(); ++i)
    changed =
        std::max(changed, double(std::abs(plain.albedo.data()[i] - converted.albedo.data()[i])));
  EXPECT_GT(changed, 0.01);
}

// One bounce, the miss model, no denoiser: what the closed box's known answers measure.
GiSettings closed_box_settings(TemporalMode temporal) {
  GiSettings s;
  s.bounces = 1;
  s.miss = MissMode::kAuto;
  s.denoise = DenoiseMode::kNone;
  s.temporal = temporal;
  return s;
}

// A camera of 120 degrees (104 down) at the centre of a closed cube of half-size 1, drawn into
// blank_scene: each pixel the nearest face (the largest component of its ray reaches |1|
// first), its normal facing the camera; no light.
Frame closed_box(const GiSettings& settings) {
  Frame f = blank_scene(settings, 120.0, 0.0f);
  GBuffer& g = f.g;
  const Camera& cam = g.camera;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) {
      const double r[3] = {(x + 0.5 - cam.cx) / cam.fx, (cam.cy - (y + 0.5)) / cam.fy, 1.0};
      int axis = 2;
      for (int a = 0; a < 2; ++a)
        if (std::fabs(r[a]) > std::fabs(r[axis])) axis = a;
      g.depth.at(0, x, y) = static_cast<float>(1.0 / std::fabs(r[axis]));
      g.normal.at(axis, x, y) = r[axis] > 0 ? -1.0f : 1.0f;
    }
  return f;
}

// The camera at the centre of a closed cube [-1, 1]^3 whose every surface reflects 0.5, looking
// at a wall: the frame's border shows the ceiling, the floor and both side walls. Under a black
// environment the miss model finds no sky and every direction enclosed (behind the camera as
// much as the sides; forward 0.89, the wall ahead being mostly away from the border), so a miss
// brings the box's light: one bounce is 0.5 to 4% (measured 0.484 at worst).
TEST(Pipeline, TheMissModelClosesAClosedBox) {
  const GiSettings base = closed_box_settings(TemporalMode::kNone);
  Frame f = closed_box(base);
  GBuffer& g = f.g;
  g.direct = Image(g.width(), g.height(), 3, 0.5f);  // this layout's direct light has the albedo
  const detail::Environment black;
  const detail::MissModel model(g, MissMode::kAuto, black);
  for (float sky : model.sky_by_elevation()) EXPECT_EQ(sky, 0.0f);
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    GiSettings s = base;
    s.tracer = tracer;
    const Image indirect = Pipeline(f.seq, s).indirect_light(g);
    for (int c = 0; c < 3; ++c)
      for (std::size_t p = 0; p < indirect.plane_size(); ++p)
        ASSERT_NEAR(indirect.plane(c)[p], 0.5f, 0.02f) << model.describe() << " at " << p;
  }
}

// The temporal window levels its frames' misses: frames lit alike take the mean colours of
// their misses (sideways, up, down), frames lit otherwise keep their own. In a closed box (one
// bounce: each ray brings the light of a face it hits, or the cube's colours, the border's light),
// three frames lit 0.5 but for a band three pixels wide along the frame's edges, 0.75, 0.5 and
// 0.4 (the surfaces they share within 1.25x of each other): the brighter border gives the
// brighter misses, and each frame's light moves by its shares of them x (the mean - its own),
// down for the first, up for the last. The same when the middle frame shows a block near the
// camera reflecting 4 (a lamp entering the view: its mean light over twice the others', the
// surfaces it shares with them as theirs). Lit 0.2, 0.5 and 1.1 everywhere (a change of lighting,
// not of view), each keeps its light as it is.
TEST(Pipeline, TheWindowLevelsTheMissesOfFramesLitAlike) {
  GiSettings s = closed_box_settings(TemporalMode::kWindow);
  s.trace_scale = 1;
  Frame f = closed_box(s);
  const GBuffer& g = f.g;
  const int w = g.width(), h = g.height();
  f.seq.frames_on_disk = {1, 2, 3};  // a shot, so that the plan has a window
  const auto lit = [&](int frame, float inside, float edge) {
    GBuffer out = g;
    out.frame = frame;
    out.direct = Image(w, h, 3, inside);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (std::min(std::min(x, w - 1 - x), std::min(y, h - 1 - y)) < 3)
          for (int c = 0; c < 3; ++c) out.direct.at(c, x, y) = edge;
    return out;
  };
  const auto with_lamp = [&](GBuffer frame) {
    for (int y = h / 4; y < 3 * h / 4; ++y)
      for (int x = w / 4; x < 3 * w / 4; ++x) {
        frame.depth.at(0, x, y) = 0.3f;
        for (int c = 0; c < 3; ++c) {
          frame.normal.at(c, x, y) = c == 2 ? -1.0f : 0.0f;
          frame.direct.at(c, x, y) = 4.0f;
        }
      }
    return frame;
  };
  const auto mean_of = [](const Image& image) {
    double sum = 0;
    for (float v : image.data()) sum += v;
    return sum / static_cast<double>(image.data().size());
  };
  const auto expect_levelled = [&](const Pipeline& pipeline,
                                   const std::vector<Pipeline::TracedLight>& t) {
    const std::vector<Image> levelled = pipeline.window_lights({&t[0], &t[1], &t[2]});
    ASSERT_EQ(levelled.size(), 3u);
    EXPECT_GT(t[0].miss_colours[0][1], t[2].miss_colours[0][1] + 0.05f);
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(t[k].miss_shares.channels(), 3);
      float want_delta[3][3];
      for (int grp = 0; grp < 3; ++grp)
        for (int c = 0; c < 3; ++c)
          want_delta[grp][c] =
              (t[0].miss_colours[grp][c] + t[1].miss_colours[grp][c] + t[2].miss_colours[grp][c]) /
                  3 -
              t[k].miss_colours[grp][c];
      for (std::size_t p = 0; p < t[k].light.plane_size(); ++p)
        for (int c = 0; c < 3; ++c) {
          float want = t[k].light.plane(c)[p];
          for (int grp = 0; grp < 3; ++grp)
            want += t[k].miss_shares.plane(grp)[p] * want_delta[grp][c];
          ASSERT_NEAR(levelled[k].plane(c)[p], std::max(want, 0.0f), 1e-5f)
              << "frame " << k << " at " << p;
        }
    }
    EXPECT_LT(mean_of(levelled[0]), mean_of(t[0].light) - 0.01);
    EXPECT_GT(mean_of(levelled[2]), mean_of(t[2].light) + 0.01);
  };
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    s.tracer = tracer;
    const Pipeline pipeline(f.seq, s);
    ASSERT_EQ(pipeline.plan().temporal, TemporalMode::kWindow);
    {
      SCOPED_TRACE("lit alike, other borders");
      expect_levelled(pipeline, {pipeline.trace_light(lit(1, 0.5f, 0.75f)),
                                 pipeline.trace_light(lit(2, 0.5f, 0.5f)),
                                 pipeline.trace_light(lit(3, 0.5f, 0.4f))});
    }
    {
      SCOPED_TRACE("lit alike, a lamp in the view");
      const std::vector<Pipeline::TracedLight> t = {
          pipeline.trace_light(lit(1, 0.5f, 0.75f)),
          pipeline.trace_light(with_lamp(lit(2, 0.5f, 0.5f))),
          pipeline.trace_light(lit(3, 0.5f, 0.4f))};
      ASSERT_GT(mean_of(t[1].reflected), 2.0 * mean_of(t[0].reflected));
      expect_levelled(pipeline, t);
    }
    {
      SCOPED_TRACE("lit otherwise");
      const std::vector<Pipeline::TracedLight> t = {pipeline.trace_light(lit(1, 0.2f, 0.2f)),
                                                    pipeline.trace_light(lit(2, 0.5f, 0.5f)),
                                                    pipeline.trace_light(lit(3, 1.1f, 1.1f))};
      const std::vector<Image> levelled = pipeline.window_lights({&t[0], &t[1], &t[2]});
      for (int k = 0; k < 3; ++k) EXPECT_EQ(levelled[k].data(), t[k].light.data()) << k;
    }
  }
}

// A wall facing the camera over a lit ground, sky above (background) and no world transform (up
// is camera +y). The model sees sky above the wall and ground below, enclosed only downwards
// (and forwards, by the wall): upward misses go to the (black) sky, and under that open sky the
// ground reaches the horizon, so every miss below it meets the ground. The wall's lower
// hemisphere is all ground: its indirect light is half the ground's radiance (the view factor of
// a plane to a perpendicular infinite plane), whether the rays meet the ground the frame shows
// or leave it. In a studio (the same set before an unlit backdrop, no sky) nothing says the floor
// goes on: the wall gets less than half of that.
TEST(Pipeline, AWallFacingTheCameraGetsTheGroundBehindTheCamera) {
  GiSettings base = converged_settings();
  base.bounces = 1;
  const double ground_y = -1.6, wall_z = 10, wall_top = 1.0;
  const float ground_light = 0.5f;  // reflected = 2 x this (direct includes albedo here)
  for (const bool studio : {false, true}) {
    SCOPED_TRACE(studio ? "studio" : "exterior");
    Frame f = blank_scene(base, 60.0, std::numeric_limits<float>::infinity());
    GBuffer& g = f.g;
    const int w = g.width(), h = g.height();
    const Camera& cam = g.camera;
    std::vector<std::size_t> wall;
    std::vector<bool> what_ground(static_cast<std::size_t>(w) * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double ry = (cam.cy - (y + 0.5)) / cam.fy;
        const std::size_t p = static_cast<std::size_t>(y) * w + x;
        if (ry < 0 && ground_y / ry < wall_z) {  // the ground, lit
          g.depth.plane(0)[p] = static_cast<float>(ground_y / ry);
          g.normal.plane(1)[p] = 1.0f;
          what_ground[p] = true;
        } else if (ry * wall_z < wall_top) {  // the wall, unlit
          g.depth.plane(0)[p] = static_cast<float>(wall_z);
          g.normal.plane(2)[p] = -1.0f;
          if (ry * wall_z > ground_y + 0.5 && y > h / 3) wall.push_back(p);
        } else if (studio) {  // an unlit backdrop far behind the wall
          g.depth.plane(0)[p] = static_cast<float>(4 * wall_z);
          g.normal.plane(2)[p] = -1.0f;
        }
      }
    ASSERT_GE(wall.size(), 20u);
    const detail::Environment black;
    const detail::MissModel model(g, MissMode::kAuto, black);
    const auto& sky = model.sky_by_elevation();
    const std::string decided = model.describe();
    EXPECT_EQ(sky.front(), 0.0f);                 // below: ground
    EXPECT_EQ(sky.back(), studio ? 0.0f : 1.0f);  // above: sky, or the backdrop
    EXPECT_NE(decided.find(studio ? "ground to the horizon 0.00" : "ground to the horizon 1.00"),
              std::string::npos)
        << decided;
    if (!studio) {
      EXPECT_NE(decided.find("enclosed right left up down forward back: 0.00 0.00 0.00 1.00"),
                std::string::npos)
          << decided;
    }
    // The wall's mean indirect light with black misses and with the model, over a lit and a
    // black ground: the model adds light, and only the ground's.
    auto wall_light = [&](Tracer tracer, MissMode miss, float ground) {
      GBuffer lit = g;
      for (std::size_t p = 0; p < what_ground.size(); ++p)
        if (what_ground[p])
          for (int c = 0; c < 3; ++c) lit.direct.plane(c)[p] = 2 * ground;
      GiSettings s = base;
      s.tracer = tracer;
      s.miss = miss;
      const Image indirect = Pipeline(f.seq, s).indirect_light(lit);
      double mean = 0;
      for (std::size_t p : wall) mean += indirect.plane(0)[p] / wall.size();
      return mean;
    };
    const double half = 0.5 * 2 * ground_light;  // half the ground's radiance
    for (Tracer tracer : kTracers) {
      SCOPED_TRACE(tracer_name(tracer));
      const double black_misses = wall_light(tracer, MissMode::kEnvironment, ground_light);
      const double modelled = wall_light(tracer, MissMode::kAuto, ground_light);
      std::printf("%s, %s: the wall gets %.4f with black misses, %.4f with the miss model\n",
                  studio ? "studio" : "exterior", tracer_name(tracer), black_misses, modelled);
      EXPECT_GT(modelled, black_misses + 0.01);
      if (studio) {
        EXPECT_LT(modelled, 0.8 * half);
      } else {
        EXPECT_NEAR(modelled, half, 0.05 * half);  // measured 0.485 (slices), 0.477 (march)
      }
      EXPECT_EQ(wall_light(tracer, MissMode::kAuto, 0.0f), 0.0);
    }
  }
}

// Thin features get thin slabs (surface_model.h): a wall 10 away with poles 0.5 in front of it,
// one and two pixels wide. The wall's slab is --thickness; a pole's is kDepthPerWidth x its width
// over the focal length, rounded up to a step of thickness / 64; a floor seen at a slant is a wide
// surface, so its slab is the whole thickness too.
TEST(Pipeline, ThinFeaturesGetThinSlabs) {
  GiSettings base;
  Frame f = blank_scene(base, 60.0, 10.0f);
  GBuffer& g = f.g;
  const int w = g.width(), h = g.height();
  const Camera& cam = g.camera;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double ry = (cam.cy - (y + 0.5)) / cam.fy;
      if (ry < 0 && -1.6 / ry < 10) {  // the floor
        g.depth.at(0, x, y) = static_cast<float>(-1.6 / ry);
        g.normal.at(1, x, y) = 1.0f;
      } else {
        if (x == 20 || x == 40 || x == 41) g.depth.at(0, x, y) = 9.5f;  // the poles
        g.normal.at(2, x, y) = -1.0f;
      }
    }
  const detail::SurfaceModel model{0.1f};
  const Image t = detail::feature_thickness(g, model);
  const float step = model.thickness / detail::kThicknessSteps;
  auto thin = [&](int pixels) {
    return step * std::ceil(detail::kDepthPerWidth * pixels / static_cast<float>(cam.fx) / step);
  };
  const int wall_row = 5, floor_row = h - 3;
  EXPECT_FLOAT_EQ(t.at(0, 20, wall_row), thin(1));
  EXPECT_FLOAT_EQ(t.at(0, 40, wall_row), thin(2));
  EXPECT_FLOAT_EQ(t.at(0, 41, wall_row), thin(2));
  EXPECT_LT(thin(1), 0.4f * model.thickness);  // 0.0375: a pole of 0.18 at 9.5 is 0.36 deep
  for (const int x : {0, 10, 19, 21, 30, 42, w - 1}) {
    EXPECT_EQ(t.at(0, x, wall_row), model.thickness) << x;
    EXPECT_EQ(t.at(0, x, floor_row), model.thickness) << x;
  }
}

// Light passes behind a thin pole: a wall facing the camera over a lit ground (as above), with
// a pole half a unit in front of it, one pixel wide (0.18 at depth 9.5) and unlit. Two pixels
// beside the pole the wall gets the light it gets without the pole (the pole hides too little
// of the ground for these rays to meet it). Were the pole's slab a tenth of its depth (0.95,
// reaching past the wall), it would wall the wall off: 0.81 of the light there with both
// tracers, as before thin features.
TEST(Pipeline, LightPassesBehindAThinPole) {
  GiSettings base = converged_settings();
  base.bounces = 1;
  const double ground_y = -1.6, wall_z = 10;
  auto wall_light = [&](Tracer tracer, bool pole) {
    Frame f = blank_scene(base, 60.0, std::numeric_limits<float>::infinity());
    GBuffer& g = f.g;
    const int w = g.width(), h = g.height();
    const Camera& cam = g.camera;
    std::vector<std::size_t> beside;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double ry = (cam.cy - (y + 0.5)) / cam.fy;
        if (ry < 0 && ground_y / ry < wall_z) {  // the ground, lit
          g.depth.at(0, x, y) = static_cast<float>(ground_y / ry);
          g.normal.at(1, x, y) = 1.0f;
          for (int c = 0; c < 3; ++c) g.direct.at(c, x, y) = 1.0f;
        } else if (ry * wall_z < 1.0) {  // the wall and the pole, unlit
          g.depth.at(0, x, y) = pole && x == w / 2 ? 9.5f : static_cast<float>(wall_z);
          g.normal.at(2, x, y) = -1.0f;
          if ((x == w / 2 - 2 || x == w / 2 + 2) && ry * wall_z > ground_y + 0.5)
            beside.push_back(static_cast<std::size_t>(y) * w + x);
        }
      }
    GiSettings s = base;
    s.tracer = tracer;
    const Image indirect = Pipeline(f.seq, s).indirect_light(g);
    double mean = 0;
    for (std::size_t p : beside) mean += indirect.plane(0)[p] / beside.size();
    return mean;
  };
  for (Tracer tracer : kTracers) {
    SCOPED_TRACE(tracer_name(tracer));
    const double open = wall_light(tracer, false), behind_pole = wall_light(tracer, true);
    std::printf("%s: beside the pole the wall gets %.4f, without the pole %.4f (%.2f)\n",
                tracer_name(tracer), behind_pole, open, behind_pole / open);
    EXPECT_GT(open, 0.1);
    EXPECT_NEAR(behind_pole, open, 0.03 * open);
  }
}

// A room: the frame shows a floor and a ceiling along its border and a far wall between them,
// no side wall and no sky. The border says nothing faces right, left or back, but a room has
// walls on the sides the frame cannot show: those are enclosed. Ahead the far wall is on
// screen, and forward stays as measured: 0.70 for the room's band of wall across the frame,
// 0 in a long hall whose far wall is too far for a pixel. Without the ceiling (a floor before
// a backdrop: a studio) the sides stay open.
TEST(Pipeline, AFloorAndACeilingWithoutSkyCloseTheRoomsSides) {
  GiSettings base;
  struct Case {
    const char* name;
    double far;
    bool ceiling;
    const char* enclosed;
  };
  for (const Case& c : {Case{"room", 20, true, "1.00 1.00 1.00 1.00 0.70 1.00"},
                        Case{"hall", 400, true, "1.00 1.00 1.00 1.00 0.00 1.00"},
                        Case{"studio", 20, false, "0.00 0.00 0.00 1.00 1.00 0.00"}}) {
    SCOPED_TRACE(c.name);
    Frame f = blank_scene(base, 60.0, std::numeric_limits<float>::infinity());
    GBuffer& g = f.g;
    const Camera& cam = g.camera;
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x) {
        const double ry = (cam.cy - (y + 0.5)) / cam.fy;
        const double floor_y = -1.5, ceiling_y = 1.5;
        float depth = static_cast<float>(c.far);
        int axis = 2;
        float sign = -1;
        if (ry < 0 && floor_y / ry < c.far) {
          depth = static_cast<float>(floor_y / ry), axis = 1, sign = 1;
        } else if (c.ceiling && ry > 0 && ceiling_y / ry < c.far) {
          depth = static_cast<float>(ceiling_y / ry), axis = 1, sign = -1;
        }
        g.depth.at(0, x, y) = depth;
        g.normal.at(axis, x, y) = sign;
      }
    const detail::Environment black;
    const std::string decided = detail::MissModel(g, MissMode::kAuto, black).describe();
    EXPECT_NE(decided.find(std::string("enclosed right left up down forward back: ") + c.enclosed),
              std::string::npos)
        << decided;
  }
}

// Behind the camera the sky is the frame's most open side's, unless both sides are enclosed.
// Ground below; ahead a wall over the right half only, above the horizon on the left the sky
// (an open square): straight back at 10.8 degrees up is all sky, ahead half of it, sideways
// ahead's. With tall walls along both sides as well (a street), behind is as ahead.
TEST(Pipeline, BehindTheCameraTheSkyIsTheMostOpenSidesUnlessBothSidesAreEnclosed) {
  GiSettings base;
  const float inf = std::numeric_limits<float>::infinity();
  for (const bool street : {false, true}) {
    SCOPED_TRACE(street ? "street" : "square");
    Frame f = blank_scene(base, 60.0, inf);
    GBuffer& g = f.g;
    const Camera& cam = g.camera;
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x) {
        const double r[3] = {(x + 0.5 - cam.cx) / cam.fx, (cam.cy - (y + 0.5)) / cam.fy, 1.0};
        double t = inf;
        int axis = -1;
        float sign = 1;
        auto meet = [&](int a, double at, float facing, auto&& inside) {
          const double s = at / r[a];
          if (s > 0 && s < t && inside(s)) t = s, axis = a, sign = facing;
        };
        meet(1, -1.6, 1.0f, [](double) { return true; });               // the ground
        meet(2, 10.0, -1.0f, [&](double s) { return r[0] * s >= 0; });  // the wall ahead
        if (street)
          for (const float side : {-1.0f, 1.0f})  // walls along the view, 20 high
            meet(0, 3.0 * side, -side, [&](double s) { return r[1] * s < 20 && s < 40; });
        if (axis < 0) continue;
        g.depth.at(0, x, y) = static_cast<float>(t);
        g.normal.at(axis, x, y) = sign;
      }
    const detail::Environment black;
    const detail::MissModel model(g, MissMode::kAuto, black);
    const float up = 0.1875f, level = std::sqrt(1 - up * up);  // a bin's centre: no blending
    const float ahead = model.sky_share({0, up, level}), back = model.sky_share({0, up, -level});
    const float side = model.sky_share({level, up, 0});
    std::printf("%s: sky ahead %.3f, sideways %.3f, behind %.3f; %s\n",
                street ? "street" : "square", ahead, side, back, model.describe().c_str());
    EXPECT_EQ(side, ahead);
    if (street) {
      EXPECT_GT(ahead, 0.0f);  // the gap between the side walls shows sky
      EXPECT_LT(ahead, 0.5f);
      EXPECT_NEAR(back, ahead, 0.01f);
    } else {
      EXPECT_NEAR(ahead, 0.5f, 0.05f);
      EXPECT_NEAR(back, 1.0f, 1e-5f);
    }
  }
}

// --normals depth: on the ground plane and on the sample room the normals the reader derives
// from depth are the file's wherever the pixel and its neighbours lie on one flat surface
// (within 1 degree on every pixel of the plane; on 85% of the room's, measured 90%: its boxes and
// walls are flat),
// and the plan says where they come from.
TEST(Pipeline, NormalsFromDepthMatchTheFlatSurfacesOfThePass) {
  for (const auto& [pattern, share] :
       {std::pair{"plane/plane.0001.exr", 0.99}, std::pair{"sample/sample.0001.exr", 0.85}}) {
    SCOPED_TRACE(pattern);
    InputOptions in;
    in.pattern = std::string(SSGI_TESTDATA_DIR) + "/" + pattern;
    in.normals = "pass";
    const SequenceInfo pass_seq = open_sequence(in);
    in.normals = "depth";
    const SequenceInfo depth_seq = open_sequence(in);
    ASSERT_FALSE(pass_seq.normals_from_depth);
    ASSERT_TRUE(depth_seq.normals_from_depth);
    const GiSettings s;
    const Plan plan = make_plan(depth_seq, s);
    bool said = false;
    for (const std::string& r : plan.reasons)
      said |= r.find("depth buffer's pixel") != std::string::npos;
    EXPECT_TRUE(said);
    const GBuffer a = read_gbuffer(pass_seq, pass_seq.frames.front(), plan.roles, in);
    const GBuffer b = read_gbuffer(depth_seq, depth_seq.frames.front(), plan.roles, in);
    std::size_t surfaces = 0, agree = 0;
    for (int y = 0; y < a.height(); ++y)
      for (int x = 0; x < a.width(); ++x) {
        if (!a.is_surface(x, y)) continue;
        ++surfaces;
        double dot = 0;
        for (int c = 0; c < 3; ++c) dot += a.normal.at(c, x, y) * b.normal.at(c, x, y);
        agree += dot > std::cos(M_PI / 180) ? 1 : 0;
      }
    std::printf("%s: %zu of %zu normals within 1 degree\n", pattern, agree, surfaces);
    ASSERT_GT(surfaces, 100u);
    EXPECT_GE(static_cast<double>(agree), share * surfaces);
  }
}

// --normals depth on features one pixel across: a wall facing the camera with a pole (a column,
// 0.3 nearer) and a rod (a row, 0.1 nearer) before it. Either one-sided difference across the
// pole or the rod runs to the wall and would turn its normal sideways; a pixel both of whose
// neighbours lie nearer or both farther faces the camera along that axis, so every pixel here
// gets the wall's normal, the camera's -z.
TEST(Pipeline, NormalsFromDepthTurnFeaturesOnePixelAcrossToTheCamera) {
  const Box2i window{0, 0, 64, 48};
  const Camera cam = camera_from_fov(60.0, window);
  Image depth(64, 48, 1, 10.0f);
  for (int y = 0; y < 48; ++y) depth.at(0, 20, y) = 9.7f;  // the pole
  for (int x = 0; x < 64; ++x) depth.at(0, x, 30) = 9.9f;  // the rod
  const Image n = detail::normals_from_depth(depth, cam, window, window);
  for (const auto& [x, y] : {std::pair{20, 10}, std::pair{40, 30}, std::pair{20, 30},
                             std::pair{19, 10}, std::pair{21, 10}, std::pair{40, 29}}) {
    SCOPED_TRACE(std::to_string(x) + "," + std::to_string(y));
    EXPECT_NEAR(n.at(0, x, y), 0.0f, 1e-4f);
    EXPECT_NEAR(n.at(1, x, y), 0.0f, 1e-4f);
    EXPECT_NEAR(n.at(2, x, y), -1.0f, 1e-6f);
  }
}

}  // namespace
}  // namespace ssgi
