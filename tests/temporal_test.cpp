// The temporal stage: reprojection lands where the surface point is, disocclusions leave no
// trail, the window averages exactly and is the same whatever the chunking or thread count,
// and the EMA's dependence on where a run starts decays as (1 - alpha)^frames.
#include "gi/temporal.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <deque>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "io/frame_reader.h"
#include "ssgi/camera.h"
#include "ssgi/error.h"
#include "ssgi/threads.h"

namespace ssgi::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Inputs: the committed fixtures (testdata/README.md), and a synthetic shot made here.

std::vector<GBuffer> load_fixture(const std::string& name) {
  InputOptions in;
  in.pattern = std::string(SSGI_TESTDATA_DIR) + "/" + name + "/" + name + ".####.exr";
  const SequenceInfo seq = open_sequence(in);
  const RoleMask roles = role_bit(Role::kDepth) | role_bit(Role::kNormal) | role_bit(Role::kMotion);
  std::vector<GBuffer> frames;
  for (int f : seq.frames) frames.push_back(read_gbuffer(seq, f, roles, in));
  return frames;
}

// A camera sliding sideways (world = camera axes: x right, y up, z forward) over a floor and a
// wall, with a sphere moving in front of them. Ray cast through pixel centres; motion vectors
// project each hit point, moved with its object, through the neighbouring frames' cameras.
struct Shot {
  int width = 64, height = 48;
  double hfov_deg = 60;
  Imath::V3d camera_velocity{0.1, 0, 0};  // per frame
  Imath::V3d sphere_start{-1.5, -0.3, 5}, sphere_velocity{0.4, 0, 0.05};
  double sphere_radius = 0.7;
  double wall_z = 8, floor_y = -1;

  Imath::V3d camera_position(int frame) const { return camera_velocity * frame; }
  Imath::V3d sphere_centre(int frame) const { return sphere_start + sphere_velocity * frame; }
  Camera camera(int frame) const {
    Camera c = camera_from_fov(hfov_deg, {0, 0, width, height});
    c.has_world_transform = true;
    const Imath::V3d p = camera_position(frame);
    c.world_to_camera[3][0] = -p.x;
    c.world_to_camera[3][1] = -p.y;
    c.world_to_camera[3][2] = -p.z;
    return c;
  }
  GBuffer render(int frame) const;
};

// Display position of world point p seen by `camera` placed at `position`.
Imath::V3d project(const Camera& camera, const Imath::V3d& position, const Imath::V3d& p) {
  double px, py;
  const Imath::V3d c{p.x - position.x, p.y - position.y, p.z - position.z};
  camera.project(c, &px, &py);
  return {px, py, c.z};
}

GBuffer Shot::render(int frame) const {
  GBuffer g;
  g.frame = frame;
  g.path = "synthetic." + std::to_string(frame);
  g.display_window = g.data_window = {0, 0, width, height};
  g.camera = camera(frame);
  g.depth = Image(width, height, 1, kInf);
  g.normal = Image(width, height, 3);
  g.motion_prev = Image(width, height, 2);
  g.motion_next = Image(width, height, 2);
  const Imath::V3d eye = camera_position(frame), centre = sphere_centre(frame);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double px = x + 0.5, py = y + 0.5;
      const Imath::V3d d = g.camera.unproject(px, py, 1.0);  // d.z = 1: t is planar depth
      double t = wall_z - eye.z;
      Imath::V3d n{0, 0, -1}, velocity{0, 0, 0};
      if (d.y < 0) {
        const double t_floor = (floor_y - eye.y) / d.y;
        if (t_floor < t) {
          t = t_floor;
          n = {0, 1, 0};
        }
      }
      const Imath::V3d oc{eye.x - centre.x, eye.y - centre.y, eye.z - centre.z};
      const double a = d.x * d.x + d.y * d.y + d.z * d.z, b = oc.x * d.x + oc.y * d.y + oc.z * d.z;
      const double disc =
          b * b - a * (oc.x * oc.x + oc.y * oc.y + oc.z * oc.z - sphere_radius * sphere_radius);
      if (disc > 0) {
        const double t_sphere = (-b - std::sqrt(disc)) / a;
        if (t_sphere > 0 && t_sphere < t) {
          t = t_sphere;
          const Imath::V3d p = eye + d * t;
          n = (p - centre) * (1 / sphere_radius);
          velocity = sphere_velocity;
        }
      }
      const Imath::V3d p = eye + d * t;
      g.depth.at(0, x, y) = static_cast<float>(t);
      g.normal.at(0, x, y) = static_cast<float>(n.x);
      g.normal.at(1, x, y) = static_cast<float>(n.y);
      g.normal.at(2, x, y) = static_cast<float>(n.z);
      const Imath::V3d prev =
          project(camera(frame - 1), camera_position(frame - 1), p + velocity * -1.0);
      const Imath::V3d next = project(camera(frame + 1), camera_position(frame + 1), p + velocity);
      g.motion_prev.at(0, x, y) = static_cast<float>(prev.x - px);
      g.motion_prev.at(1, x, y) = static_cast<float>(prev.y - py);
      g.motion_next.at(0, x, y) = static_cast<float>(next.x - px);
      g.motion_next.at(1, x, y) = static_cast<float>(next.y - py);
    }
  }
  return g;
}

std::vector<GBuffer> render_shot(const Shot& shot, int first, int last) {
  std::vector<GBuffer> frames;
  for (int f = first; f <= last; ++f) frames.push_back(shot.render(f));
  return frames;
}

// A uniform number in [0, 1) from the generator's bits alone (std::uniform_real_distribution
// differs between standard libraries).
float uniform(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * 0x1p-24f; }

// Smooth light over the image (at most 1.5% change per pixel), varying by channel.
float base_light(int c, int x, int y) {
  return (0.5f + 0.3f * std::sin(0.05f * x + c) * std::cos(0.04f * y)) * (1.0f - 0.2f * c);
}

// base_light times (1 + uniform noise in +-amplitude), a fixed seed per frame.
Image noisy_light(const GBuffer& g, float amplitude) {
  std::mt19937 rng(1234u + static_cast<std::uint32_t>(g.frame));
  Image light(g.width(), g.height(), 3);
  for (int c = 0; c < 3; ++c) {
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width(); ++x) {
        const float noise = amplitude * (2 * uniform(rng) - 1);
        if (g.is_surface(x, y)) light.at(c, x, y) = base_light(c, x, y) * (1 + noise);
      }
    }
  }
  return light;
}

std::vector<const GBuffer*> pointers(const std::vector<GBuffer>& frames) {
  std::vector<const GBuffer*> p;
  for (const GBuffer& g : frames) p.push_back(&g);
  return p;
}
std::vector<const Image*> pointers(const std::vector<Image>& images) {
  std::vector<const Image*> p;
  for (const Image& i : images) p.push_back(&i);
  return p;
}

bool same_bits(const Image& a, const Image& b) {
  return a.width() == b.width() && a.height() == b.height() && a.channels() == b.channels() &&
         std::memcmp(a.data().data(), b.data().data(), a.bytes()) == 0;
}

bool all_finite(const Image& image) {
  return std::all_of(image.data().begin(), image.data().end(),
                     [](float v) { return std::isfinite(v); });
}

// The frame loop as run.cpp is to drive it, on frames already in memory: a ring of at most
// 2K + 1 frames, filled ahead of the output frame and emptied behind it, over the frames
// [first - K, last + K] that exist. Returns the outputs for first..last.

std::vector<Image> run_window(const std::vector<GBuffer>& shot, const std::vector<Image>& light,
                              int first, int last, int radius) {
  std::deque<int> ring;  // indices into shot
  int next = std::max(0, first - radius);
  std::vector<Image> outputs;
  for (int f = first; f <= last; ++f) {
    while (next < static_cast<int>(shot.size()) && next <= f + radius) ring.push_back(next++);
    while (ring.front() < f - radius) ring.pop_front();
    EXPECT_LE(static_cast<int>(ring.size()), 2 * radius + 1);
    std::vector<const GBuffer*> frames;
    std::vector<const Image*> images;
    int center = -1;
    for (int i : ring) {
      if (i == f) center = static_cast<int>(frames.size());
      frames.push_back(&shot[i]);
      images.push_back(&light[i]);
    }
    outputs.push_back(temporal_window(frames, images, center, radius));
  }
  return outputs;
}

// The EMA over frames first..last of `shot`, starting afresh at `first`; returns the last.
Image run_ema(const std::vector<GBuffer>& shot, const std::vector<Image>& light, int first,
              int last, float alpha) {
  Image output = light[first];
  for (int f = first + 1; f <= last; ++f)
    output = temporal_ema(shot[f], light[f], shot[f - 1], output, alpha);
  return output;
}

// A static camera over a static scene.

TEST(TemporalWindow, StaticSceneGivesTheFrameAverage) {
  // Ten pixel-identical frames: every neighbour reprojects onto itself. Noise of +-5% keeps
  // any frame within 15% of the 3x3 mean of any other (plus the light's slope), inside the
  // clip box (its floor is 25% of the mean), so nothing is clipped and the window is the plain
  // mean of its frames, up to float rounding (accumulated in double).
  const std::vector<GBuffer> shot = load_fixture("static");
  std::vector<Image> light;
  for (const GBuffer& g : shot) light.push_back(noisy_light(g, 0.05f));
  const int radius = 2;
  const std::vector<Image> out = run_window(shot, light, 0, 9, radius);
  for (int f = 0; f < 10; ++f) {
    const int lo = std::max(0, f - radius), hi = std::min(9, f + radius);
    for (std::size_t i = 0; i < out[f].data().size(); ++i) {
      double mean = 0;
      for (int k = lo; k <= hi; ++k) mean += light[k].data()[i];
      mean /= hi - lo + 1;
      ASSERT_NEAR(out[f].data()[i], mean, 1e-6 * std::abs(mean)) << "frame " << f + 1;
    }
  }
}

TEST(TemporalWindow, StaticNoiseVarianceFallsByTheWindowSize) {
  // Independent noise in each of 2K + 1 = 5 frames: the mean's variance is 1/5 of a frame's.
  // Relative noise over all surface pixels of the six frames with a full window (~9000
  // samples, standard error of a variance ~1.5%): within 10% of 5.
  const std::vector<GBuffer> shot = load_fixture("static");
  std::vector<Image> light;
  for (const GBuffer& g : shot) light.push_back(noisy_light(g, 0.05f));
  const std::vector<Image> out = run_window(shot, light, 2, 7, 2);
  double in_var = 0, out_var = 0;
  int n = 0;
  for (int k = 0; k < 6; ++k) {
    const GBuffer& g = shot[k + 2];
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width(); ++x) {
        if (!g.is_surface(x, y)) continue;
        const double base = base_light(0, x, y);
        in_var += std::pow(light[k + 2].at(0, x, y) / base - 1, 2);
        out_var += std::pow(out[k].at(0, x, y) / base - 1, 2);
        ++n;
      }
    }
  }
  const double ratio = in_var / out_var;
  std::printf("noise variance ratio over a +-2 window: %.3f (%d samples)\n", ratio, n);
  EXPECT_NEAR(ratio, 5.0, 0.5);
}

// Reprojection lands on the same surface point.

// Light that says where it is: channel 0 = display x, channel 1 = display y of the pixel centre.
Image coordinates(const GBuffer& g) {
  Image image(g.width(), g.height(), 3, 1.0f);
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      image.at(0, x, y) = x + 0.5f;
      image.at(1, x, y) = y + 0.5f;
    }
  }
  return image;
}

// Pan: the camera slides sideways, so a point keeps its depth and moves by the same disparity
// (the Vector pass, exact) every frame: it is at p + n * vector n frames later. The back wall
// moves exactly 2 px per frame. Landing position = the reprojected coordinate image.
struct Landing {
  double max_error = 0;
  int measured = 0, valid = 0, surface = 0;
};

Landing pan_landing(const std::vector<GBuffer>& pan, int from, int to) {
  std::vector<const GBuffer*> frames = pointers(pan);
  Image valid;
  const Image landed = reproject(frames, from, to, coordinates(pan[to]), &valid);
  const GBuffer& g = pan[from];
  const GBuffer& o = pan[to];
  const Image& vector = to > from ? g.motion_next : g.motion_prev;
  const int n = std::abs(to - from);
  Landing l;
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!g.is_surface(x, y)) continue;
      ++l.surface;
      if (!(valid.at(0, x, y) > 0)) continue;
      ++l.valid;
      const double ex = x + 0.5 + n * vector.at(0, x, y), ey = y + 0.5 + n * vector.at(1, x, y);
      if (g.depth.at(0, x, y) == 6.5f) {
        EXPECT_EQ(ex, x + 0.5 - 2.0 * (to - from));
      }
      // Measured where the 2x2 taps around the expected position are one flat surface, so
      // that the bilinear mean of the coordinates is the position itself.
      const int x0 = static_cast<int>(std::floor(ex - 0.5)),
                y0 = static_cast<int>(std::floor(ey - 0.5));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= o.width() || y0 + 1 >= o.height()) continue;
      bool flat = true;
      for (int j = 0; j < 2; ++j) {
        for (int k = 0; k < 2; ++k) {
          for (int c = 0; c < 3; ++c)
            flat = flat && o.normal.at(c, x0 + k, y0 + j) == o.normal.at(c, x0, y0);
          flat = flat && std::abs(o.depth.at(0, x0 + k, y0 + j) / o.depth.at(0, x0, y0) - 1) < 0.05;
        }
      }
      if (!flat) continue;
      ++l.measured;
      l.max_error =
          std::max(l.max_error, std::hypot(landed.at(0, x, y) - ex, landed.at(1, x, y) - ey));
    }
  }
  return l;
}

TEST(Reproject, PanLandsWithinHalfAPixel) {
  std::vector<GBuffer> pan = load_fixture("pan");
  for (bool cameras : {true, false}) {
    // Without world transforms the cameras count as still, and the motion vectors (chained
    // through the frame in between for two frames) carry every pixel instead.
    if (!cameras) {
      for (GBuffer& g : pan) g.camera.has_world_transform = false;
    }
    for (auto [from, to] : {std::pair{2, 3}, std::pair{3, 2}, std::pair{2, 4}, std::pair{4, 2}}) {
      const Landing l = pan_landing(pan, from, to);
      std::printf(
          "pan %s, frame %d -> %d: %d of %d surface pixels with history, landing error "
          "max %.2g px over %d\n",
          cameras ? "cameras" : "vectors", from + 1, to + 1, l.valid, l.surface, l.max_error,
          l.measured);
      // Flat surfaces: ~half of the pixels.
      EXPECT_GT(l.measured, l.surface * 4 / 10);
      EXPECT_LT(l.max_error, 0.5);
      // History is lost where surfaces leave the screen (>= 2 px per frame) or come out from
      // behind nearer ones: 6% of the pixels one frame away, 13% two frames away.
      EXPECT_GT(l.valid, l.surface * (std::abs(to - from) == 1 ? 90 : 82) / 100);
    }
  }
}

TEST(Reproject, TwoFrameOverloadMatchesTheRing) {
  const std::vector<GBuffer> pan = load_fixture("pan");
  const Image history = coordinates(pan[3]);
  Image valid_pair, valid_ring;
  const Image pair = reproject(pan[2], pan[3], history, &valid_pair);
  const Image ring = reproject(pointers(pan), 2, 3, history, &valid_ring);
  EXPECT_TRUE(same_bits(pair, ring));
  EXPECT_TRUE(same_bits(valid_pair, valid_ring));
}

TEST(Reproject, SeveralHistoriesAtOnceAreEachTheOneHistoryForm) {
  // Through the moving sphere's vectors two frames away and along the pan's cameras; the second
  // history has a non-finite patch, where the first is found but the second has fewer taps.
  for (const char* fixture : {"moving", "pan"}) {
    const std::vector<GBuffer> shot = load_fixture(fixture);
    const std::vector<const GBuffer*> frames = pointers(shot);
    const int from = 3, to = 1;
    const Image first = coordinates(shot[to]);
    Image second(first.width(), first.height(), 3), third = first;
    for (int c = 0; c < 3; ++c)
      for (int y = 0; y < second.height(); ++y)
        for (int x = 0; x < second.width(); ++x) {
          second.at(c, x, y) = 0.5f + 0.25f * static_cast<float>(c) + 0.01f * static_cast<float>(y);
          third.at(c, x, y) *= 2.0f;
        }
    second.at(1, 10, 10) = std::numeric_limits<float>::quiet_NaN();
    Image valid, valid_one;
    const std::vector<Image> all = reproject(frames, from, to, {&first, &second, &third}, &valid);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_TRUE(same_bits(all[0], reproject(frames, from, to, first, &valid_one))) << fixture;
    EXPECT_TRUE(same_bits(valid, valid_one)) << fixture;
    EXPECT_TRUE(same_bits(all[2], reproject(frames, from, to, third, nullptr))) << fixture;
    // The second as its own form wherever that finds it; where only the first is found, 0.
    Image valid_second;
    const Image second_alone = reproject(frames, from, to, second, &valid_second);
    int found = 0;
    for (int y = 0; y < valid.height(); ++y)
      for (int x = 0; x < valid.width(); ++x) {
        if (!(valid.at(0, x, y) > 0)) continue;
        ++found;
        for (int c = 0; c < 3; ++c)
          EXPECT_EQ(all[1].at(c, x, y),
                    valid_second.at(0, x, y) > 0 ? second_alone.at(c, x, y) : 0.0f);
      }
    EXPECT_GT(found, valid.width() * valid.height() / 4) << fixture;
  }
  const std::vector<GBuffer> shot = load_fixture("pan");
  const Image light = coordinates(shot[1]);
  EXPECT_THROW(reproject(pointers(shot), 0, 1, std::vector<const Image*>{}, nullptr), Error);
  EXPECT_THROW(reproject(pointers(shot), 0, 1, {&light, &light, &light, &light}, nullptr), Error);
}

// Disocclusion: the sphere of `moving` crosses the wall at ~5.9 px per frame.

// The sphere is what moves (the camera is still): its pixels, from the Vector pass.
using Mask = std::vector<std::vector<bool>>;  // [y][x]
Mask sphere_mask(const GBuffer& g) {
  Mask m(g.height(), std::vector<bool>(g.width()));
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      m[y][x] = g.is_surface(x, y) &&
                std::hypot(g.motion_prev.at(0, x, y), g.motion_prev.at(1, x, y)) > 1;
  return m;
}
std::vector<Mask> sphere_masks(const std::vector<GBuffer>& shot) {
  std::vector<Mask> masks;
  for (const GBuffer& g : shot) masks.push_back(sphere_mask(g));
  return masks;
}

// Light 10 on the sphere, 1 on everything else: history of the sphere on a static pixel is
// a trail of 9 / (frames averaged).
std::vector<Image> sphere_light(const std::vector<GBuffer>& shot, const std::vector<Mask>& sphere) {
  std::vector<Image> light;
  for (std::size_t k = 0; k < shot.size(); ++k) {
    const GBuffer& g = shot[k];
    Image l(g.width(), g.height(), 3);
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x)
        for (int c = 0; c < 3; ++c)
          if (g.is_surface(x, y)) l.at(c, x, y) = sphere[k][y][x] ? 10.0f : 1.0f;
    light.push_back(l);
  }
  return light;
}

struct Trail {
  double worst = 0;  // largest |light - 1| on static pixels the sphere covered earlier/later
  int pixels = 0;
  double sphere_mean = 0;  // mean light on the sphere (10: its own history was found)
};

Trail measure_trail(const std::vector<GBuffer>& shot, const std::vector<Mask>& sphere, int f,
                    int lo, int hi, const Image& out) {
  const GBuffer& g = shot[f];
  Trail t;
  int sphere_pixels = 0;
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!g.is_surface(x, y)) continue;
      if (sphere[f][y][x]) {
        t.sphere_mean += out.at(0, x, y);
        ++sphere_pixels;
        continue;
      }
      bool covered = false;
      for (int k = lo; k <= hi; ++k) covered = covered || sphere[k][y][x];
      if (!covered) continue;
      ++t.pixels;
      for (int c = 0; c < 3; ++c) t.worst = std::max(t.worst, std::abs(out.at(c, x, y) - 1.0));
    }
  }
  t.sphere_mean /= std::max(1, sphere_pixels);
  return t;
}

TEST(TemporalWindow, MovingSphereLeavesNoTrail) {
  // A trail would be >= 9/5 on pixels every window frame but one saw as sphere; the depth
  // (plane) test rejects all of it, so the bound is float rounding.
  std::vector<GBuffer> shot = load_fixture("moving");
  const std::vector<Mask> sphere = sphere_masks(shot);
  const std::vector<Image> light = sphere_light(shot, sphere);
  for (bool vectors : {true, false}) {
    if (!vectors) {
      for (GBuffer& g : shot) g.motion_prev = g.motion_next = Image();
    }
    const std::vector<Image> out = run_window(shot, light, 2, 3, 2);
    for (int f : {2, 3}) {
      const Trail t = measure_trail(shot, sphere, f, f - 2, f + 2, out[f - 2]);
      std::printf(
          "moving, %s, window frame %d: trail max %.3g over %d uncovered pixels, "
          "sphere mean %.4f\n",
          vectors ? "vectors" : "no vectors", f + 1, t.worst, t.pixels, t.sphere_mean);
      EXPECT_GT(t.pixels, 100);
      EXPECT_LT(t.worst, 1e-6);
      EXPECT_NEAR(t.sphere_mean, 10.0, 1e-4);
    }
  }
}

TEST(TemporalEma, MovingSphereLeavesNoTrail) {
  const std::vector<GBuffer> shot = load_fixture("moving");
  const std::vector<Mask> sphere = sphere_masks(shot);
  const std::vector<Image> light = sphere_light(shot, sphere);
  for (int last = 1; last < 6; ++last) {
    const Image out = run_ema(shot, light, 0, last, 0.1f);
    const Trail t = measure_trail(shot, sphere, last, 0, last - 1, out);
    EXPECT_LT(t.worst, 1e-6) << "frame " << last + 1;
    EXPECT_NEAR(t.sphere_mean, 10.0, 1e-4);
  }
}

TEST(Reproject, MovingSphereFollowsItsVectors) {
  // The sphere finds its own history one and two frames away (through the frame in between),
  // except for a few pixels at its rim.
  const std::vector<GBuffer> shot = load_fixture("moving");
  const Mask sphere = sphere_mask(shot[3]);
  const std::vector<const GBuffer*> frames = pointers(shot);
  const Image history(shot[0].width(), shot[0].height(), 3, 1.0f);
  for (int to : {1, 2, 4, 5}) {
    Image valid;
    reproject(frames, 3, to, history, &valid);
    int pixels = 0, found = 0;
    for (int y = 0; y < shot[3].height(); ++y) {
      for (int x = 0; x < shot[3].width(); ++x) {
        if (!sphere[y][x]) continue;
        ++pixels;
        found += valid.at(0, x, y) > 0;
      }
    }
    std::printf("moving sphere, frame 4 -> %d: history on %d of %d sphere pixels\n", to + 1, found,
                pixels);
    EXPECT_GT(found, pixels * 8 / 10);
  }
}

// Chunking and threads.

TEST(TemporalWindow, AnyChunkingGivesTheSameBits) {
  // Ten frames of a panning camera and a moving sphere, +-2 frames: one run, chunks of 3,
  // and frame by frame, each chunk reading the K frames beyond its ends.
  const Shot spec;
  const std::vector<GBuffer> shot = render_shot(spec, 1, 10);
  std::vector<Image> light;
  for (const GBuffer& g : shot) light.push_back(noisy_light(g, 0.3f));
  const std::vector<Image> whole = run_window(shot, light, 0, 9, 2);
  for (int chunk : {3, 1}) {
    for (int first = 0; first < 10; first += chunk) {
      const int last = std::min(9, first + chunk - 1);
      const std::vector<Image> part = run_window(shot, light, first, last, 2);
      for (int f = first; f <= last; ++f)
        EXPECT_TRUE(same_bits(part[f - first], whole[f])) << "chunk " << chunk << " frame " << f;
    }
  }
  // And the window did something: the output is not the input.
  EXPECT_FALSE(same_bits(whole[5], light[5]));
}

TEST(TemporalEma, PrerollBoundsTheChunkDifference) {
  // An EMA run that starts N frames before the frame it writes differs from a run over the
  // whole shot by (1 - alpha)^N times the difference at its start, which is at most the
  // largest light value. Noise of +-30% makes the clip act; the sphere adds disocclusions.
  const float alpha = 0.1f;
  Shot spec;
  spec.width = 32;
  spec.height = 24;
  spec.camera_velocity = {0.01, 0, 0};
  spec.sphere_velocity = {0.03, 0, 0};
  const int last = 80;
  const std::vector<GBuffer> shot = render_shot(spec, 0, last);
  std::vector<Image> light;
  float peak = 0;
  for (const GBuffer& g : shot) {
    light.push_back(noisy_light(g, 0.3f));
    peak =
        std::max(peak, *std::max_element(light.back().data().begin(), light.back().data().end()));
  }
  const Image full = run_ema(shot, light, 0, last, alpha);
  for (int preroll : {10, 22, 44, 66}) {
    const Image chunk = run_ema(shot, light, last - preroll, last, alpha);
    double worst = 0;
    for (std::size_t i = 0; i < full.data().size(); ++i)
      worst = std::max(worst, static_cast<double>(std::abs(full.data()[i] - chunk.data()[i])));
    const double bound = std::pow(1.0 - alpha, preroll);
    std::printf("EMA alpha %.2f, pre-roll %d: max difference %.3g of peak (bound %.3g)\n", alpha,
                preroll, worst / peak, bound);
    EXPECT_LE(worst / peak, bound);
  }
  EXPECT_EQ(ema_preroll_frames(alpha, 1e-3), 66);
  EXPECT_EQ(ema_preroll_frames(0.5f, 1e-3), 10);
  EXPECT_EQ(ema_preroll_frames(1.0f, 1e-3), 0);
  EXPECT_THROW(ema_preroll_frames(0.0f, 1e-3), Error);
  EXPECT_THROW(ema_preroll_frames(0.1f, 0.0), Error);
}

TEST(Temporal, ThreadCountDoesNotChangeTheBits) {
  const Shot spec;
  const std::vector<GBuffer> shot = render_shot(spec, 1, 5);
  std::vector<Image> light;
  for (const GBuffer& g : shot) light.push_back(noisy_light(g, 0.3f));
  Image window[2], ema[2];
  for (int threads : {1, 2}) {
    const ThreadLimit limit(threads);
    window[threads - 1] = temporal_window(pointers(shot), pointers(light), 2, 2);
    ema[threads - 1] = run_ema(shot, light, 0, 4, 0.1f);
  }
  EXPECT_TRUE(same_bits(window[0], window[1]));
  EXPECT_TRUE(same_bits(ema[0], ema[1]));
}

// The clip and the EMA's formula.

TEST(ClipHistory, PullsOutliersIntoTheNeighbourhoodBox) {
  // A constant 1 (sigma 0): the box is 1 +- 0.25 (the floor). History 1.05 is inside and
  // kept; 5 is moved towards the mean onto the box; invalid pixels are left alone.
  const Shot spec;
  const GBuffer g = spec.render(0);
  const Image current(g.width(), g.height(), 3, 1.0f);
  Image history(g.width(), g.height(), 3, 1.05f);
  Image valid(g.width(), g.height(), 1, 1.0f);
  history.at(0, 10, 10) = history.at(1, 10, 10) = history.at(2, 10, 10) = 5.0f;
  history.at(0, 20, 10) = 7.0f;  // clipped towards the mean, keeping the direction
  valid.at(0, 30, 10) = 0;
  history.at(0, 30, 10) = 9.0f;
  clip_history(g, current, valid, &history);
  EXPECT_FLOAT_EQ(history.at(0, 5, 5), 1.05f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(history.at(c, 10, 10), 1.25, 1e-6);
  EXPECT_NEAR(history.at(0, 20, 10), 1.25, 1e-6);
  EXPECT_NEAR(history.at(1, 20, 10), 1.0 + 0.05 * 0.25 / 6.0, 1e-6);
  EXPECT_FLOAT_EQ(history.at(0, 30, 10), 9.0f);
}

TEST(TemporalEma, BlendsAlphaOfTheCurrentFrame) {
  // A still camera over a static scene: the history lands on itself, inside the clip box, so
  // the result is alpha * current + (1 - alpha) * previous output exactly; with nothing to
  // reproject (previous frame all background) it is the current light.
  Shot spec;
  spec.camera_velocity = {0, 0, 0};
  spec.sphere_velocity = {0, 0, 0};
  const GBuffer prev = spec.render(0), cur = spec.render(1);
  const Image current(cur.width(), cur.height(), 3, 1.0f);
  const Image previous(cur.width(), cur.height(), 3, 1.08f);
  const Image out = temporal_ema(cur, current, prev, previous, 0.25f);
  for (float v : out.data()) EXPECT_NEAR(v, 0.25 * 1.0 + 0.75 * 1.08, 1e-6);

  GBuffer empty = prev;
  empty.depth = Image(cur.width(), cur.height(), 1, kInf);
  EXPECT_TRUE(same_bits(temporal_ema(cur, current, empty, previous, 0.25f), current));
  EXPECT_THROW(temporal_ema(cur, current, prev, previous, 0.0f), Error);
  EXPECT_THROW(temporal_ema(cur, current, prev, previous, 1.5f), Error);
}

TEST(TemporalWindow, SingleFrameIsTheFrame) {
  const Shot spec;
  const std::vector<GBuffer> shot = render_shot(spec, 1, 1);
  const std::vector<Image> light = {noisy_light(shot[0], 0.3f)};
  EXPECT_TRUE(same_bits(temporal_window(pointers(shot), pointers(light), 0, 2), light[0]));
  // Radius 0: the neighbours in the ring are ignored.
  const std::vector<GBuffer> three = render_shot(spec, 1, 3);
  std::vector<Image> lights;
  for (const GBuffer& g : three) lights.push_back(noisy_light(g, 0.3f));
  EXPECT_TRUE(same_bits(temporal_window(pointers(three), pointers(lights), 1, 0), lights[1]));
}

// Lit alike or not: the light of the surfaces two frames both show decides, not the frames'
// means. The synthetic shot's wall and floor reflect 0.4 and 0.8 (per channel a little
// less); the sphere, moving 1.5 per frame (more than its diameter, so no point of it is where
// it was), is what a lamp entering the view is. Frame 1 against frame 2: the same static light
// and a sphere 40x as bright (the means 1.4x apart): ratio 1; the static light doubled in
// frame 2: ratio 1/2 either way round; a camera 100 units on (the views share nothing): none.
TEST(SharedLight, ComparesTheSurfacesBothFramesShow) {
  Shot spec;
  spec.sphere_velocity = {1.5, 0, 0};
  spec.sphere_start = {-0.8, -0.3, 5};
  const std::vector<GBuffer> shot = render_shot(spec, 1, 2);
  // The wall faces -z, the floor +y; the sphere's normals are neither.
  const auto lit = [](const GBuffer& g, float scale, float sphere) {
    Image light(g.width(), g.height(), 3);
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x) {
        if (!g.is_surface(x, y)) continue;
        const bool wall = g.normal.at(2, x, y)<-0.999f, floor = g.normal.at(1, x, y)> 0.999f;
        for (int c = 0; c < 3; ++c)
          light.at(c, x, y) =
              wall || floor ? scale * (floor ? 0.8f : 0.4f) * (1 - 0.1f * c) : sphere;
      }
    return light;
  };
  const auto mean = [](const Image& image) {
    double sum = 0;
    for (float v : image.data()) sum += v;
    return sum / static_cast<double>(image.data().size());
  };
  const Image a = lit(shot[0], 1.0f, 0.5f);
  const Image b_lamp = lit(shot[1], 1.0f, 20.0f), b_doubled = lit(shot[1], 2.0f, 1.0f);
  ASSERT_GT(mean(b_lamp), 1.4 * mean(a));
  EXPECT_NEAR(shared_light_ratio(shot[0], a, shot[1], b_lamp), 1.0, 0.02);
  EXPECT_NEAR(shared_light_ratio(shot[0], a, shot[1], b_doubled), 0.5, 0.01);
  EXPECT_NEAR(shared_light_ratio(shot[1], b_doubled, shot[0], a), 2.0, 0.04);
  Shot far = spec;
  far.camera_velocity = {100, 0, 0};
  const std::vector<GBuffer> apart = render_shot(far, 1, 2);
  EXPECT_TRUE(std::isnan(shared_light_ratio(apart[0], lit(apart[0], 1.0f, 0.5f), apart[1],
                                            lit(apart[1], 1.0f, 0.5f))));
  EXPECT_THROW(shared_light_ratio(shot[0], Image(3, 3, 3), shot[1], b_lamp), Error);
}

// Which sample holds a point: a wall alone (the floor far below, the sphere behind the camera),
// its light the column's number + 1 in each frame, the camera sliding right so that the wall
// moves left by 0.3 or 0.7 pixels. At 0.3 every point's pixel is the same column in both frames
// (ratio exactly 1); at 0.7 it is the column to the left in the later frame (an earlier column
// number: the earlier frame is the brighter, either way round the lattices are taken). The same
// with both frames' data windows 5 pixels into their display windows.
TEST(SharedLight, FindsThePixelThatHoldsThePoint) {
  for (const double shift : {0.3, 0.7}) {
    Shot spec;
    spec.floor_y = -1e4;
    spec.sphere_start = {0, 0, -100};
    spec.sphere_velocity = {0, 0, 0};
    const double fx = spec.width / 2.0 / std::tan(spec.hfov_deg * M_PI / 360.0);
    spec.camera_velocity = {shift * spec.wall_z / fx, 0, 0};
    std::vector<GBuffer> shot = render_shot(spec, 1, 2);
    std::vector<Image> light;
    for (const GBuffer& g : shot) {
      Image l(g.width(), g.height(), 3);
      for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x)
          for (int c = 0; c < 3; ++c) l.at(c, x, y) = static_cast<float>(x + 1);
      light.push_back(std::move(l));
    }
    const double ratio = shared_light_ratio(shot[0], light[0], shot[1], light[1]);
    SCOPED_TRACE(shift);
    if (shift < 0.5)
      EXPECT_EQ(ratio, 1.0);
    else
      EXPECT_GT(ratio, 1.01);
    EXPECT_DOUBLE_EQ(shared_light_ratio(shot[1], light[1], shot[0], light[0]), 1.0 / ratio);
    for (GBuffer& g : shot) {
      g.display_window = {-5, 0, g.width() + 5, g.height()};
      g.camera.cx += 5;
    }
    EXPECT_EQ(shared_light_ratio(shot[0], light[0], shot[1], light[1]), ratio);
  }
}

// Numerical extremes: never a NaN, never a crash.

TEST(Temporal, ExtremeInputsGiveFiniteResults) {
  const Shot spec;
  std::vector<GBuffer> shot = render_shot(spec, 1, 3);
  std::vector<Image> light;
  for (const GBuffer& g : shot) light.push_back(noisy_light(g, 0.3f));
  const float depths[] = {kNaN, kInf, -kInf, -1.0f, 0.0f, 1e-30f, 1e-4f, 1e10f, 3e38f};
  const float values[] = {kNaN, kInf, -kInf, 1e30f, -1e30f, 1e-40f, 3e38f};
  const float motions[] = {kNaN, kInf, 1e30f, -1e30f, 1e9f, -0.5f};
  for (std::size_t k = 0; k < shot.size(); ++k) {
    GBuffer& g = shot[k];
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width(); ++x) {
        const int h = x * 7 + y * 13 + static_cast<int>(k) * 3;
        if (h % 5 == 0) g.depth.at(0, x, y) = depths[h % 9];
        if (h % 7 == 0) {
          for (int c = 0; c < 3; ++c) g.normal.at(c, x, y) = h % 2 ? 0.0f : kNaN;
        }
        if (h % 3 == 0) light[k].at(h % 3, x, y) = values[h % 7];
        if (h % 11 == 0) g.motion_prev.at(h % 2, x, y) = motions[h % 6];
        if (h % 4 == 0) g.motion_next.at(h % 2, x, y) = motions[(h / 4) % 6];
      }
    }
  }
  const std::vector<const GBuffer*> frames = pointers(shot);
  for (int to : {0, 2}) {
    Image valid;
    const Image r = reproject(frames, 1, to, light[to], &valid);
    EXPECT_TRUE(all_finite(r));
  }
  EXPECT_TRUE(all_finite(temporal_window(frames, pointers(light), 1, 2)));
  EXPECT_TRUE(all_finite(temporal_ema(shot[1], light[1], shot[0], light[0], 0.1f)));
  // Large but finite light stays finite through the variance (computed in double).
  for (Image& l : light) std::fill(l.data().begin(), l.data().end(), 3e38f);
  EXPECT_TRUE(all_finite(temporal_window(frames, pointers(light), 1, 2)));
  EXPECT_TRUE(all_finite(temporal_ema(shot[1], light[1], shot[0], light[0], 0.1f)));
}

TEST(Temporal, MismatchedInputsThrow) {
  const Shot spec;
  const std::vector<GBuffer> shot = render_shot(spec, 1, 2);
  const Image small(4, 4, 3);
  EXPECT_THROW(reproject(shot[0], shot[1], small, nullptr), Error);
  const std::vector<Image> light = {small, small};
  EXPECT_THROW(temporal_window(pointers(shot), pointers(light), 0, 1), Error);
  Shot other = spec;
  other.width = 32;
  const GBuffer g = other.render(2);
  EXPECT_THROW(reproject(shot[0], g, Image(32, 48, 3), nullptr), Error);
}

}  // namespace
}  // namespace ssgi::detail
