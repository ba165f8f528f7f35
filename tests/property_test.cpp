// Properties of whole runs on seeded random G-buffers (reader, pipeline and writer, in process):
// shots of random small sizes, plausible scenes with or without random extremes (NaN, inf,
// 1e30, denormals, negatives, zeros, background depth) in any pass. Whatever the input, ssgi's
// layers are finite and the input's channels pass through bit for bit; on plausible inputs one
// bounce is never negative nor brighter than the brightest source; the bits do not depend on
// the thread count or on how the shot is cut into chunks.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "settings.h"
#include "ssgi/run.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

constexpr float kInf = std::numeric_limits<float>::infinity();

// A uniform number in [0, 1) from the generator's bits alone (the standard distributions differ
// between libraries).
float uniform(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * 0x1p-24f; }

// The Blender passes of a frame, by channel name, each a float plane.
struct RandomFrame {
  int width = 0, height = 0;
  std::map<std::string, std::vector<float>> planes;
};

const std::array<const char*, 3> kRgb = {"R", "G", "B"};
const std::array<const char*, 3> kXyz = {"X", "Y", "Z"};

std::string pass(const std::string& name, const char* component) {
  return "ViewLayer." + name + "." + component;
}

// A plausible scene: a floor, a back wall and a box of random placement seen by a --fov camera
// (planar depth, camera-space normals facing the camera), albedo in [0, 1], direct light in
// [0, 4] with some pixels unlit, and some background (Blender's 1e10).
RandomFrame plausible_frame(std::mt19937& rng, int w, int h) {
  RandomFrame f;
  f.width = w, f.height = h;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  auto plane = [&](const std::string& name) -> std::vector<float>& {
    return f.planes[name] = std::vector<float>(n, 0.0f);
  };
  std::vector<float>& depth = plane(pass("Depth", "Z"));
  std::array<std::vector<float>*, 3> normal, albedo, direct;
  for (int c = 0; c < 3; ++c) {
    normal[c] = &plane(pass("Normal", kXyz[c]));
    albedo[c] = &plane(pass("DiffCol", kRgb[c]));
    direct[c] = &plane(pass("DiffDir", kRgb[c]));
  }
  for (int c = 0; c < 4; ++c) plane(pass("Combined", c < 3 ? kRgb[c] : "A"));
  const float wall = 2 + 8 * uniform(rng), horizon = 0.3f + 0.5f * uniform(rng);
  const int bx0 = static_cast<int>(uniform(rng) * w), by0 = static_cast<int>(uniform(rng) * h);
  const int bx1 = bx0 + 1 + static_cast<int>(uniform(rng) * w / 2);
  const int by1 = by0 + 1 + static_cast<int>(uniform(rng) * h / 2);
  const float box = wall * (0.3f + 0.5f * uniform(rng));
  const float sky = uniform(rng) * 0.2f;  // share of background pixels at the top
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      const float v = (y + 0.5f) / static_cast<float>(h);
      std::array<float, 3> nrm = {0, 0, -1};
      float z = wall;
      if (v > horizon) {  // the floor, nearer further down
        z = std::min(wall, wall * (1 - horizon) / (v - horizon + 1e-3f));
        nrm = {0, 1, 0};
      }
      if (x >= bx0 && x < bx1 && y >= by0 && y < by1) z = box, nrm = {0, 0, -1};
      if (v < sky) z = 1e10f, nrm = {0, 0, 0};
      depth[p] = z;
      for (int c = 0; c < 3; ++c) {
        (*normal[c])[p] = nrm[c];
        (*albedo[c])[p] = z < 1e9f ? uniform(rng) : 0.0f;
        (*direct[c])[p] = z < 1e9f && uniform(rng) < 0.7f ? 4 * uniform(rng) : 0.0f;
      }
    }
  }
  return f;
}

// Values renderers and broken files write.
float extreme(std::mt19937& rng) {
  const float values[] = {std::numeric_limits<float>::quiet_NaN(),
                          kInf,
                          -kInf,
                          1e30f,
                          -1e30f,
                          1e-40f,  // denormal
                          -3.0f,
                          0.0f,
                          1e10f,  // Blender's background depth
                          1e-5f,
                          65504.0f,
                          std::numeric_limits<float>::max()};
  return values[rng() % (sizeof values / sizeof values[0])];
}

// Sets a random share (up to a fifth) of the values of random passes to extremes.
void add_extremes(std::mt19937& rng, RandomFrame* f) {
  for (auto& [name, plane] : f->planes) {
    if (uniform(rng) < 0.4f) continue;
    const float share = 0.2f * uniform(rng);
    for (float& v : plane)
      if (uniform(rng) < share) v = extreme(rng);
  }
}

void write_frame(const std::string& path, const RandomFrame& f) {
  OIIO::ImageSpec spec(f.width, f.height, static_cast<int>(f.planes.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames.clear();
  for (const auto& entry : f.planes) spec.channelnames.push_back(entry.first);
  spec.alpha_channel = spec.z_channel = -1;
  spec.attribute("compression", "zip");
  const std::size_t n = static_cast<std::size_t>(f.width) * f.height;
  const int nc = spec.nchannels;
  std::vector<float> interleaved(n * nc);
  int c = 0;
  for (const auto& entry : f.planes) {
    for (std::size_t p = 0; p < n; ++p) interleaved[p * nc + c] = entry.second[p];
    ++c;
  }
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, spec) &&
              out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()) && out->close())
      << path << ": " << OIIO::geterror();
}

RandomFrame read_frame(const std::string& path) {
  RandomFrame f;
  auto in = OIIO::ImageInput::open(path);
  EXPECT_TRUE(in) << path << ": " << OIIO::geterror();
  if (!in) return f;
  const OIIO::ImageSpec& spec = in->spec();
  f.width = spec.width, f.height = spec.height;
  const std::size_t n = static_cast<std::size_t>(f.width) * f.height;
  std::vector<float> interleaved(n * spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, interleaved.data()));
  for (int c = 0; c < spec.nchannels; ++c) {
    std::vector<float>& plane = f.planes[spec.channelnames[c]];
    plane.resize(n);
    for (std::size_t p = 0; p < n; ++p) plane[p] = interleaved[p * spec.nchannels + c];
  }
  return f;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

const std::vector<std::string> kOurChannels = {
    "R", "G", "B", "A", "indirect.R", "indirect.G", "indirect.B", "gi.R", "gi.G", "gi.B"};

// A random case: its shot on disk and the settings it runs with.
struct Case {
  std::string dir;
  int width = 0, height = 0, frames = 1;
  bool extremes = false;
  RunOptions options;
  std::vector<RandomFrame> inputs;
};

Case make_case(std::uint32_t seed, bool extremes, int frames) {
  std::mt19937 rng(seed);
  Case c;
  c.dir = (fs::path(testing::TempDir()) /
           ("ssgi_property_" + std::to_string(seed) + (extremes ? "x" : "")))
              .string();
  fs::remove_all(c.dir);
  fs::create_directories(c.dir);
  // Sizes from 1 pixel to 48, thin ones included.
  c.width = 1 + static_cast<int>(rng() % 48);
  c.height = rng() % 4 == 0 ? 1 + static_cast<int>(rng() % 3) : 1 + static_cast<int>(rng() % 40);
  c.frames = frames;
  c.extremes = extremes;
  for (int i = 0; i < frames; ++i) {
    RandomFrame f = plausible_frame(rng, c.width, c.height);
    if (extremes) add_extremes(rng, &f);
    write_frame(c.dir + "/in." + std::to_string(1001 + i) + ".exr", f);
    c.inputs.push_back(std::move(f));
  }
  RunOptions& o = c.options;
  o.input.pattern = c.dir + "/in.####.exr";
  o.input.layout = "blender";
  o.input.camera.hfov_deg = 20 + 140 * uniform(rng);
  o.output = c.dir + "/out/out.####.exr";
  GiSettings& gi = o.gi;
  const char* presets[] = {"draft", "default", "final"};
  apply_preset(presets[rng() % 3], &gi);
  gi.tracer = static_cast<Tracer>(rng() % 3);
  if (gi.tracer != Tracer::kSlices) gi.rays = 1 + static_cast<int>(rng() % 8);
  gi.bounces = 1 + static_cast<int>(rng() % 3);
  gi.miss = static_cast<MissMode>(rng() % 4);
  if (gi.miss == MissMode::kExtend && gi.tracer != Tracer::kScreenSpace) gi.miss = MissMode::kAuto;
  gi.env_color = {uniform(rng), uniform(rng), uniform(rng)};
  gi.seed = rng();
  // Half the shots of several frames: a camera that turns and moves between frames (a sidecar
  // with each frame's world transform), the slice tracer and --multiframe on, which continues
  // its missed rays through the other frames' depth buffers.
  if (frames > 1 && rng() % 2 == 0) {
    const std::string sidecar = c.dir + "/cameras.json";
    std::FILE* file = std::fopen(sidecar.c_str(), "w");
    std::fprintf(file, "{\"frames\": [");
    const float turn = (uniform(rng) - 0.5f) * 0.2f, move = (uniform(rng) - 0.5f) * 2.0f;
    for (int i = 0; i < frames; ++i) {
      const double a = turn * i, co = std::cos(a), si = std::sin(a);
      std::fprintf(file,
                   "%s{\"frame\": %d, \"hfov_deg\": %.6f, \"worldToCamera\": [%.9f, 0, %.9f, "
                   "0, 0, 1, 0, 0, %.9f, 0, %.9f, 0, %.9f, 0, 0, 1]}",
                   i ? ", " : "", 1001 + i, o.input.camera.hfov_deg, co, -si, si, co,
                   static_cast<double>(move * i));
    }
    std::fprintf(file, "]}\n");
    std::fclose(file);
    o.input.camera.sidecar = sidecar;
    o.input.camera.hfov_deg = 0;  // the sidecar's
    gi.multiframe = kMultiframeWindow;
    gi.tracer = Tracer::kSlices;  // the tracer whose misses it continues
    if (gi.miss == MissMode::kExtend) gi.miss = MissMode::kAuto;
  }
  return c;
}

// The output of every frame of a run of `c` with `threads` threads (0: the default), under
// `out_dir`, chunked into runs of `chunk` frames (0: one run).
std::vector<RandomFrame> run_case(const Case& c, int threads, const std::string& out_dir,
                                  int chunk = 0) {
  RunOptions o = c.options;
  o.output = c.dir + "/" + out_dir + "/out.####.exr";
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  threads);
  const int step = chunk > 0 ? chunk : c.frames;
  for (int first = 0; first < c.frames; first += step) {
    o.input.frames = std::to_string(1001 + first) + "-" +
                     std::to_string(1001 + std::min(c.frames, first + step) - 1);
    const RunReport report = run_sequence(o);
    for (const FrameReport& f : report.frames) EXPECT_TRUE(f.ok) << f.error_file << ": " << f.error;
  }
  std::vector<RandomFrame> outputs;
  for (int i = 0; i < c.frames; ++i)
    outputs.push_back(
        read_frame(c.dir + "/" + out_dir + "/out." + std::to_string(1001 + i) + ".exr"));
  return outputs;
}

std::string describe(const Case& c) {
  return c.dir + " (" + std::to_string(c.width) + "x" + std::to_string(c.height) + ", tracer " +
         std::to_string(static_cast<int>(c.options.gi.tracer)) + ", " +
         std::to_string(c.options.gi.bounces) + " bounces, miss " +
         miss_mode_name(c.options.gi.miss) +
         (c.options.gi.multiframe ? ", moving camera, multiframe" : "") + ")";
}

// Whatever the input: ssgi's layers finite, the input's channels as they were, bit for bit.
void expect_finite_and_passed_through(const Case& c, const std::vector<RandomFrame>& outputs) {
  for (int i = 0; i < c.frames; ++i) {
    const RandomFrame& out = outputs[i];
    for (const std::string& name : kOurChannels) {
      const auto it = out.planes.find(name);
      ASSERT_NE(it, out.planes.end()) << describe(c) << ": no " << name;
      const auto bad = std::find_if(it->second.begin(), it->second.end(),
                                    [](float v) { return !std::isfinite(v); });
      EXPECT_EQ(bad, it->second.end()) << describe(c) << ": " << name << " has " << *bad;
    }
    for (const auto& [name, plane] : c.inputs[i].planes) {
      const auto it = out.planes.find(name);
      ASSERT_NE(it, out.planes.end()) << describe(c) << ": " << name << " not passed through";
      EXPECT_TRUE(same_bits(it->second, plane)) << describe(c) << ": " << name << " changed";
    }
  }
}

// 20 shots, each plausible and with extremes, one frame, every tracer, miss mode, bounce count
// and preset among them.
TEST(Property, AnyInputGivesFiniteLayersAndPassesThroughBitForBit) {
  int lit = 0;  // runs that found light: a pipeline that writes zeros must not pass
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    for (const bool extremes : {false, true}) {
      const Case c = make_case(seed, extremes, 1);
      const std::vector<RandomFrame> outputs = run_case(c, 0, "out");
      expect_finite_and_passed_through(c, outputs);
      const std::vector<float>& indirect = outputs[0].planes.at("indirect.G");
      lit += std::any_of(indirect.begin(), indirect.end(), [](float v) { return v > 0; }) ? 1 : 0;
    }
  }
  EXPECT_GE(lit, 20);
}

// On plausible inputs (finite, albedo in [0, 1], light >= 0), with misses seeing a constant
// environment and no temporal stage: every gather weighs its hits and misses by shares of the
// hemisphere that sum to 1, and the denoiser averages with weights that sum to 1, so one bounce
// lies between 0 and the brightest light a ray can bring (the surfaces' reflected light or the
// environment), and N bounces within N times that. A tracer that sums a ray twice, or a filter
// whose weights do not sum to 1, breaks it.
TEST(Property, BouncesStayBetweenZeroAndTheBrightestSource) {
  double closest = 0;  // the largest share of its bound a pixel reached
  for (std::uint32_t seed = 100; seed < 115; ++seed) {
    Case c = make_case(seed, false, 1);
    GiSettings& gi = c.options.gi;
    gi.temporal = TemporalMode::kNone;
    if (gi.miss == MissMode::kExtend) gi.miss = MissMode::kEnvironment;
    const std::vector<RandomFrame> outputs = run_case(c, 0, "out");
    const RandomFrame& in = c.inputs[0];
    const std::size_t n = static_cast<std::size_t>(c.width) * c.height;
    for (int ch = 0; ch < 3; ++ch) {
      const std::vector<float>& albedo = in.planes.at(pass("DiffCol", kRgb[ch]));
      const std::vector<float>& direct = in.planes.at(pass("DiffDir", kRgb[ch]));
      const std::vector<float>& depth = in.planes.at(pass("Depth", "Z"));
      float brightest = gi.env_color[ch];
      for (std::size_t p = 0; p < n; ++p)
        if (depth[p] < 1e9f) brightest = std::max(brightest, albedo[p] * direct[p]);
      const float bound = brightest * static_cast<float>(gi.bounces) * (1 + 1e-4f) + 1e-6f;
      const std::vector<float>& indirect =
          outputs[0].planes.at(std::string("indirect.") + kRgb[ch]);
      for (std::size_t p = 0; p < n; ++p) {
        ASSERT_GE(indirect[p], 0.0f) << describe(c) << " pixel " << p;
        ASSERT_LE(indirect[p], bound)
            << describe(c) << " pixel " << p << ", brightest " << brightest;
        closest = std::max(closest, static_cast<double>(indirect[p]) / bound);
      }
    }
  }
  // Not a bound that nothing comes near: some pixel gets most of it.
  std::printf("largest share of the bound: %.3f\n", closest);
  EXPECT_GT(closest, 0.1);
}

// The same bits with 1 thread as with 2, and for 3 frames run as one chunk or frame by frame
// (the temporal window, and multiframe within it, read the same neighbours wherever a chunk
// starts); finite layers and the inputs passed through with a moving camera and multiframe too.
TEST(Property, SameBitsForAnyThreadCountAndChunking) {
  int multiframe = 0;
  for (std::uint32_t seed = 200; seed < 212; ++seed) {
    const Case c = make_case(seed, seed % 2 == 1, 3);
    const std::vector<RandomFrame> one = run_case(c, 1, "one");
    const std::vector<RandomFrame> two = run_case(c, 2, "two");
    const std::vector<RandomFrame> chunked = run_case(c, 2, "chunked", 1);
    for (int i = 0; i < c.frames; ++i) {
      for (const std::string& name : kOurChannels) {
        EXPECT_TRUE(same_bits(one[i].planes.at(name), two[i].planes.at(name)))
            << describe(c) << " frame " << i << " " << name << ": 1 and 2 threads differ";
        EXPECT_TRUE(same_bits(two[i].planes.at(name), chunked[i].planes.at(name)))
            << describe(c) << " frame " << i << " " << name << ": chunking changes it";
      }
    }
    expect_finite_and_passed_through(c, two);
    multiframe += c.options.gi.multiframe ? 1 : 0;
  }
  EXPECT_GE(multiframe, 3);  // the seeds draw moving cameras with multiframe, not just still ones
}

}  // namespace
}  // namespace ssgi
