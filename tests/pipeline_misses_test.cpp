// Where rays that leave the frame go: the miss model's decisions (closed box, ground, room, sky
// behind the camera) and the temporal window's levelling of the misses.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "frame_stages.h"
#include "gi/misses.h"
#include "gtest/gtest.h"
#include "pipeline_support.h"

namespace ssgi::pipeline_test {
namespace {

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
  const auto expect_levelled = [&](const std::vector<detail::TracedLight>& t) {
    const std::vector<Image> levelled = detail::level_window_misses({&t[0], &t[1], &t[2]});
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
    const detail::FrameStages pipeline(f.seq, s);
    ASSERT_EQ(pipeline.plan().temporal, TemporalMode::kWindow);
    {
      SCOPED_TRACE("lit alike, other borders");
      expect_levelled({pipeline.grid_light(lit(1, 0.5f, 0.75f)),
                       pipeline.grid_light(lit(2, 0.5f, 0.5f)),
                       pipeline.grid_light(lit(3, 0.5f, 0.4f))});
    }
    {
      SCOPED_TRACE("lit alike, a lamp in the view");
      const std::vector<detail::TracedLight> t = {
          pipeline.grid_light(lit(1, 0.5f, 0.75f)),
          pipeline.grid_light(with_lamp(lit(2, 0.5f, 0.5f))),
          pipeline.grid_light(lit(3, 0.5f, 0.4f))};
      ASSERT_GT(mean_of(t[1].reflected), 2.0 * mean_of(t[0].reflected));
      expect_levelled(t);
    }
    {
      SCOPED_TRACE("lit otherwise");
      const std::vector<detail::TracedLight> t = {pipeline.grid_light(lit(1, 0.2f, 0.2f)),
                                                  pipeline.grid_light(lit(2, 0.5f, 0.5f)),
                                                  pipeline.grid_light(lit(3, 1.1f, 1.1f))};
      const std::vector<Image> levelled = detail::level_window_misses({&t[0], &t[1], &t[2]});
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

}  // namespace
}  // namespace ssgi::pipeline_test
