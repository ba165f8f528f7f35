// What the tracers' rays find on analytic scenes: a groove's view factor and coverage, a lit
// face only a neighbouring frame shows (multiframe), hits from behind, and thin features.
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "frame_stages.h"
#include "gi/directions.h"
#include "gi/surface_model.h"
#include "gtest/gtest.h"
#include "pipeline_support.h"

namespace ssgi::pipeline_test {
namespace {

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

// Multiframe (lib/src/gi/continuation.h): a lit face that only a neighbouring frame shows. Frame 2
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
  const detail::FrameStages pipeline(seq, s);
  ASSERT_EQ(pipeline.plan().multiframe, s.temporal_radius);
  const detail::TracedLight ta = pipeline.grid_light(a), tb = pipeline.grid_light(b);
  for (float v : ta.light.data()) ASSERT_EQ(v, 0.0f);  // alone it sees no light
  const std::optional<detail::ContinuedLight> continued =
      pipeline.continue_in_window(a, {&ta, &tb}, 0);
  ASSERT_TRUE(continued);
  const Image& light = continued->light;
  const Image& coverage = continued->coverage;

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
    const detail::FrameStages p(seq, framed);
    const detail::TracedLight fa = p.grid_light(a), fb = p.grid_light(b);
    ASSERT_EQ(fa.miss_shares.channels(), 3);
    const std::optional<detail::ContinuedLight> framed_continued =
        p.continue_in_window(a, {&fa, &fb}, 0);
    ASSERT_TRUE(framed_continued);
    const Image& left = framed_continued->miss_shares;
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
  const detail::TracedLight ts = pipeline.grid_light(still);
  EXPECT_FALSE(pipeline.continue_in_window(still, {&ts, &tb}, 0));
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

}  // namespace
}  // namespace ssgi::pipeline_test
