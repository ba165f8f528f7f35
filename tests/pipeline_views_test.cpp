// Views (--view, lib/src/io/views.h and continue_missed_rays in gi/continuation.h): light that only
// a view shows, behind the camera. The scene is two parallel infinite walls: one in frame, facing
// the camera at z = kFront, dark; one behind the camera at z = -kBack, facing it and lit, so
// that it reflects kLit. Every ray of the front wall's cosine-weighted hemisphere meets the back
// wall: with one bounce its indirect light is kLit exactly. The frame alone does not show the
// back wall (its rays leave the frame behind the camera); six cube faces rendered at the camera,
// or one lat-long panorama turned into them, do.

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "frame_stages.h"
#include "gi/composite.h"
#include "gi/continuation.h"
#include "gi/misses.h"
#include "gi/slices.h"
#include "gi/surface_model.h"
#include "gi/trace_grid.h"
#include "gtest/gtest.h"
#include "io/camera.h"
#include "io/views.h"
#include "pipeline_support.h"

namespace ssgi::pipeline_test {
namespace {

constexpr double kFront = 4.0, kBack = 3.0;
constexpr float kLit = 0.8f, kAlbedo = 0.5f;

// Where the ray from the origin along world-space `d` meets a wall: its parameter (infinite
// when it meets none) and the wall's normal and reflected light. Without `back_wall`, the sky
// lies behind the camera.
struct WallHit {
  double t = std::numeric_limits<double>::infinity();
  Imath::V3d normal{0, 0, 0};
  float reflected = 0;
};

WallHit walls(const Imath::V3d& d, bool back_wall) {
  WallHit w;
  if (d.z > 1e-12) {
    w.t = kFront / d.z;
    w.normal = {0, 0, -1};
  } else if (d.z < -1e-12 && back_wall) {
    w.t = kBack / -d.z;
    w.normal = {0, 0, 1};
    w.reflected = kLit;
  }
  return w;
}

// A camera's axes (right, up, forward) in world space as its world_to_camera (row vectors;
// the camera at the origin).
Imath::M44d world_to_camera(const Imath::V3d& right, const Imath::V3d& up,
                            const Imath::V3d& forward) {
  Imath::M44d m;
  for (int i = 0; i < 3; ++i) {
    m[i][0] = right[i];
    m[i][1] = up[i];
    m[i][2] = forward[i];
  }
  return m;
}

// What a ray from the origin along a world-space direction meets.
using Scene = std::function<WallHit(const Imath::V3d&)>;

Scene two_walls(bool back_wall = true) {
  return [back_wall](const Imath::V3d& d) { return walls(d, back_wall); };
}

// The world-space direction of `camera`'s (at the origin) pixel position (x, y).
Imath::V3d world_direction(const Camera& camera, double x, double y) {
  const Imath::V3d c = camera.view_dir(x, y);
  const Imath::M44d& m = camera.world_to_camera;
  // Camera to world: the rotation's transpose (row vectors).
  return {c.x * m[0][0] + c.y * m[0][1] + c.z * m[0][2],
          c.x * m[1][0] + c.y * m[1][1] + c.z * m[1][2],
          c.x * m[2][0] + c.y * m[2][1] + c.z * m[2][2]};
}

// `scene` as seen by `camera` (at the origin) over a square or 2:1 window of `width` x `height`
// pixels: depth (planar, or the distance for a lat-long), camera-space normals, albedo, direct
// light; the sky (infinite depth) where a ray meets nothing.
GBuffer render(const Camera& camera, int width, int height, const Scene& scene = two_walls()) {
  GBuffer g;
  g.display_window = g.data_window = Box2i{0, 0, width, height};
  g.camera = camera;
  g.depth = Image(width, height, 1);
  g.normal = Image(width, height, 3);
  g.albedo = Image(width, height, 3, kAlbedo);
  g.direct = Image(width, height, 3);
  const Imath::M44d& m = camera.world_to_camera;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Imath::V3d c = camera.view_dir(x + 0.5, y + 0.5);
      const WallHit w = scene(world_direction(camera, x + 0.5, y + 0.5));
      const bool latlong = camera.projection == Projection::kLatLong;
      g.depth.at(0, x, y) = static_cast<float>(latlong ? w.t : w.t * c.z);
      for (int k = 0; k < 3; ++k) {
        g.normal.at(k, x, y) =
            static_cast<float>(w.normal.x * m[0][k] + w.normal.y * m[1][k] + w.normal.z * m[2][k]);
        g.direct.at(k, x, y) = w.reflected;
      }
    }
  return g;
}

// The six 90-degree faces of a cube at the origin, `size` pixels square.
std::vector<GBuffer> cube_faces(int size, const Scene& scene = two_walls()) {
  const Imath::V3d forward[6] = {{0, 0, 1},  {0, 0, -1}, {1, 0, 0},
                                 {-1, 0, 0}, {0, 1, 0},  {0, -1, 0}};
  const Imath::V3d up[6] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  std::vector<GBuffer> faces;
  for (int f = 0; f < 6; ++f) {
    Camera c = camera_from_fov(90.0, Box2i{0, 0, size, size});
    c.world_to_camera = world_to_camera(up[f].cross(forward[f]), up[f], forward[f]);
    c.has_world_transform = true;
    faces.push_back(render(c, size, size, scene));
  }
  return faces;
}

// `views` numbered with frame `frame`, as read_views numbers a frame's views.
std::vector<GBuffer> numbered(std::vector<GBuffer> views, int frame) {
  for (GBuffer& v : views) v.frame = frame;
  return views;
}

GiSettings view_settings() {
  GiSettings s = converged_settings();
  s.tracer = Tracer::kSlices;
  s.bounces = 1;
  s.miss = MissMode::kEnvironment;  // black: what no ray finds is 0
  return s;
}

// The frame: the front wall from a 60-degree camera at the origin (camera space is world space).
struct Shot {
  Frame f;
  explicit Shot(const GiSettings& s) : f(blank_scene(s, 60.0, static_cast<float>(kFront))) {
    GBuffer& g = f.g;
    g.camera.has_world_transform = true;
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x) {
        // The wall z = kFront facing the camera.
        g.normal.at(2, x, y) = -1.0f;
      }
  }
  // The sequence with `projections` as its views (the plan reads only how many and which).
  SequenceInfo with_views(std::vector<Projection> projections) const {
    SequenceInfo seq = f.seq;
    for (Projection p : projections) {
      ViewInfo v;
      v.pattern = "analytic";
      v.projection = p;
      seq.views.push_back(v);
    }
    return seq;
  }
};

// The mean indirect light and coverage over the frame's inner half (its edges' rays leave it
// sideways as well).
struct Means {
  double light = 0, coverage = 0;
};
Means inner_means(const Image& light, const Image& coverage) {
  Means m;
  int n = 0;
  const int w = light.width(), h = light.height();
  for (int y = h / 4; y < 3 * h / 4; ++y)
    for (int x = w / 4; x < 3 * w / 4; ++x) {
      m.light += light.at(0, x, y);
      m.coverage += coverage.at(0, x, y);
      ++n;
    }
  m.light /= n;
  m.coverage /= n;
  return m;
}

// The mean over the cosine-weighted hemisphere of point p with normal n of what `along(p, d)`
// says a ray along d brings, by a stratified quadrature (Malley's method: a uniform grid on the
// disc, lifted to the hemisphere).
template <typename Along>
double hemisphere_light(const Imath::V3d& p, const Imath::V3d& n, const Along& along) {
  const Imath::V3d u =
      (std::fabs(n.x) < 0.5 ? Imath::V3d(1, 0, 0) : Imath::V3d(0, 1, 0)).cross(n).normalized();
  const Imath::V3d v = n.cross(u);
  constexpr int kGrid = 32;
  double light = 0;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j) {
      const double r = std::sqrt((i + 0.5) / kGrid), phi = 2 * M_PI * (j + 0.5) / kGrid;
      const Imath::V3d d =
          u * (r * std::cos(phi)) + v * (r * std::sin(phi)) + n * std::sqrt(1 - r * r);
      light += along(p, d);
    }
  return light / (kGrid * kGrid);
}

// The mean indirect light over the frame's inner half (as inner_means) and what it should be
// there: at every fourth pixel each way, `expected(p)` at the front wall's point p.
template <typename Expected>
std::array<double, 2> inner_light_and_expected(const GBuffer& g, const Image& light,
                                               const Expected& expected) {
  double got = 0, want = 0;
  int n = 0;
  const int w = g.width(), h = g.height();
  for (int y = h / 4; y < 3 * h / 4; y += 4)
    for (int x = w / 4; x < 3 * w / 4; x += 4) {
      const Imath::V3d d = world_direction(g.camera, x + 0.5, y + 0.5);
      got += light.at(0, x, y);
      want += expected(d * (kFront / d.z));
      ++n;
    }
  return {got / n, want / n};
}

TEST(Views, LightBehindTheCameraIsFoundInCubeFacesAndALatLong) {
  const GiSettings s = view_settings();
  const Shot shot(s);
  const GBuffer& g = shot.f.g;

  // Without views its light is missing, and coverage says so.
  const detail::FrameStages alone(shot.f.seq, s);
  ASSERT_FALSE(alone.plan().views);
  Image coverage;
  const Means without = inner_means(alone.indirect_light(g, &coverage), coverage);
  std::printf("without views: indirect %.4f, coverage %.3f (expected 0, 0)\n", without.light,
              without.coverage);
  EXPECT_LT(without.light, 0.01 * kLit);
  EXPECT_LT(without.coverage, 0.01);

  // With the six faces it is the back wall's light.
  const detail::FrameStages with(shot.with_views({Projection::kPinhole}), s);
  ASSERT_TRUE(with.plan().views);
  const detail::LitViews faces = with.light_views(numbered(cube_faces(32), g.frame));
  ASSERT_EQ(faces.traces.size(), 6u);
  const Means cube = inner_means(with.indirect_light(g, &coverage, &faces), coverage);
  std::printf("six faces: indirect %.4f (expected %.4f), coverage %.3f\n", cube.light, kLit,
              cube.coverage);
  EXPECT_NEAR(cube.light / kLit, 1.0, 0.10);
  EXPECT_GT(cube.coverage, 0.95);

  // A lat-long panorama at the camera, turned into six faces, finds it as well.
  Camera ll = latlong_camera(Imath::M44d(), Box2i{0, 0, 256, 128}, "analytic");
  // latlong_camera flips a -z-forward header to +z forward; the analytic one is +z forward.
  ll.world_to_camera = Imath::M44d();
  const detail::FrameStages with_ll(shot.with_views({Projection::kLatLong}), s);
  const detail::LitViews from_ll =
      with_ll.light_views(numbered(detail::latlong_faces(render(ll, 256, 128)), g.frame));
  const Means pano = inner_means(with_ll.indirect_light(g, &coverage, &from_ll), coverage);
  std::printf("lat-long: indirect %.4f (expected %.4f), coverage %.3f\n", pano.light, kLit,
              pano.coverage);
  EXPECT_NEAR(pano.light / kLit, 1.0, 0.10);
  EXPECT_GT(pano.coverage, 0.95);
  EXPECT_NEAR(std::fabs(pano.light - kLit), std::fabs(cube.light - kLit), 0.1 * kLit);
}

// Without the back wall, the sky lies behind the camera, an environment of one colour: every ray
// of the front wall's hemisphere reaches it, so its indirect light is that colour. The frame
// alone shows no sky, and its miss model (--miss frame) takes what it does not show for
// surfaces like those it shows, which are dark; the six faces show the sky there.
TEST(Views, RaysThatTheViewsShowTheSkyForTakeTheEnvironment) {
  constexpr float kSky = 0.6f;
  GiSettings s = view_settings();
  s.bounces = 2;
  s.miss = MissMode::kFrame;
  s.env_color = {kSky, kSky, kSky};
  const Shot shot(s);
  const GBuffer& g = shot.f.g;

  const detail::FrameStages alone(shot.f.seq, s);
  Image coverage;
  const Means without = inner_means(alone.indirect_light(g, &coverage), coverage);
  std::printf("without views: indirect %.4f (the miss model's guess; the sky's %.4f)\n",
              without.light, kSky);
  EXPECT_LT(without.light, 0.5 * kSky);

  const detail::FrameStages with(shot.with_views({Projection::kPinhole}), s);
  const detail::LitViews faces =
      with.light_views(numbered(cube_faces(32, two_walls(false)), g.frame));
  const Means cube = inner_means(with.indirect_light(g, &coverage, &faces), coverage);
  std::printf("six faces: indirect %.4f (expected %.4f)\n", cube.light, kSky);
  EXPECT_NEAR(cube.light / kSky, 1.0, 0.10);
}

// Where a ray from point p along d meets an analytic scene.
using SceneFrom = WallHit (*)(const Imath::V3d& p, const Imath::V3d& d);

// The frame's indirect light with the six 64-pixel cube faces of `from` at the camera as its
// views.
Image light_with_faces(const Shot& shot, const GiSettings& s, SceneFrom from) {
  const detail::FrameStages with(shot.with_views({Projection::kPinhole}), s);
  const detail::LitViews faces = with.light_views(numbered(cube_faces(64,
                                                                      [from](const Imath::V3d& d) {
                                                                        return from({0, 0, 0}, d);
                                                                      }),
                                                           shot.f.g.frame));
  Image coverage;
  return with.indirect_light(shot.f.g, &coverage, &faces);
}

// A ray that passes behind something the views show and meets nothing they show takes what lay
// behind it where it was last seen (continue_missed_rays). Behind the camera, a dark ledge at z =
// -kLedge across the rows kLedgeLow..kLedgeHigh hides part of the lit back wall from the camera:
// rays from the front wall that pass above the ledge meet the back wall there, hidden. Last seen
// in front of the back wall, heading for it, they take its light; the miss model (black here)
// would give them none. Every ray of the front wall's hemisphere meets the ledge (dark) or the
// back wall (kLit): its light is kLit times the share that meets the back wall.
constexpr double kLedge = 0.5, kLedgeLow = 0.1, kLedgeHigh = 0.6;

WallHit ledge_from(const Imath::V3d& p, const Imath::V3d& d) {
  WallHit w;
  if (d.z > 1e-12) {
    w.t = (kFront - p.z) / d.z;
    w.normal = {0, 0, -1};
    return w;
  }
  if (!(d.z < -1e-12)) return w;
  if (p.z > -kLedge) {
    const double t = (-kLedge - p.z) / d.z, y = p.y + t * d.y;
    if (y >= kLedgeLow && y <= kLedgeHigh) {
      w.t = t;
      w.normal = {0, 0, 1};
      return w;
    }
  }
  w.t = (-kBack - p.z) / d.z;
  w.normal = {0, 0, 1};
  w.reflected = kLit;
  return w;
}

TEST(Views, RaysHiddenBehindWhatTheViewsShowTakeTheSurfaceTheyWereHeadingFor) {
  const GiSettings s = view_settings();
  const Shot shot(s);
  const GBuffer& g = shot.f.g;
  const Image light = light_with_faces(shot, s, ledge_from);
  const auto [got, expected] = inner_light_and_expected(g, light, [](const Imath::V3d& p) {
    return hemisphere_light(p, {0, 0, -1}, [](const Imath::V3d& o, const Imath::V3d& d) {
      return static_cast<double>(ledge_from(o, d).reflected);
    });
  });
  // The share of its rays that meet the back wall where the ledge hides it from the camera.
  const double hidden =
      hemisphere_light({0, 0, kFront}, {0, 0, -1}, [](const Imath::V3d& o, const Imath::V3d& d) {
        const WallHit w = ledge_from(o, d);
        if (!(w.reflected > 0)) return 0.0;
        const Imath::V3d at = o + w.t * d;
        const double seen = at.y / -at.z;
        return seen >= kLedgeLow / kLedge && seen <= kLedgeHigh / kLedge ? 1.0 : 0.0;
      });
  std::printf(
      "six faces: indirect %.4f, expected %.4f (%.0f%% of the front wall's centre's rays "
      "meet the back wall where the ledge hides it)\n",
      got, expected, 100 * hidden);
  ASSERT_GT(hidden, 0.1);
  EXPECT_NEAR(got / expected, 1.0, 0.05);

  // No further than --max-distance: the back wall lies beyond it from every point of the front
  // wall, so that no ray takes its light.
  GiSettings near = s;
  near.max_distance = 1.0;
  const double within = inner_light_and_expected(g, light_with_faces(shot, near, ledge_from),
                                                 [](const Imath::V3d&) { return 0.0; })[0];
  std::printf("--max-distance 1: indirect %.4f (expected 0)\n", within);
  EXPECT_LT(within, 0.01 * kLit);
}

// The views light one another in passes (FrameStages::light_views): the first continues each
// view's missed rays in the others (continue_missed_rays), the later ones bring the others' newer
// light along the same rays (source_light), which must be what the first brought for the same
// light, the rays that took a surface they were last seen heading for included. Each face of the
// ledge scene lit alone keeps its missed rays; continued in the other faces, each face's light
// from them against source_light's for the same rays and light.
TEST(Views, LaterPassesAmongViewsBringWhatTheFirstFound) {
  GiSettings s = view_settings();
  s.bounces = 3;
  const Shot shot(s);
  const detail::FrameStages stages(shot.with_views({Projection::kPinhole}), s);
  const std::vector<GBuffer> faces = numbered(cube_faces(64,
                                                         [](const Imath::V3d& d) {
                                                           return ledge_from({0, 0, 0}, d);
                                                         }),
                                              shot.f.g.frame);
  std::vector<detail::LitViews> alone;
  for (const GBuffer& face : faces) alone.push_back(stages.light_views({face}));
  std::size_t hidden = 0;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    std::vector<detail::ContinuationSource> others;
    for (std::size_t j = 0; j < faces.size(); ++j)
      if (j != i) others.push_back({alone[j].traces[0].get(), &alone[j].light[0]});
    const detail::FrameTrace& t = *alone[i].traces[0];
    const detail::Continuation continued = detail::continue_missed_rays(
        t, {t.hits.miss, t.hits.env, t.hits.cube, t.hits.continued_light}, others,
        detail::continuation_policy(detail::ContinuationPolicy::Kind::kViews), s, false, true);
    const detail::ContinuationReport& report = continued.report;
    const Image again = detail::source_light(t, continued.found, others, s);
    double first = 0, later = 0;
    for (int k = 0; k < 3; ++k)
      for (std::size_t p = 0; p < again.plane_size(); ++p) {
        first += continued.shares.continued_light.plane(k)[p];
        later += again.plane(k)[p];
      }
    std::printf("face %zu: %s; light %.4f, again %.4f\n", i, report.describe(1).c_str(), first,
                later);
    EXPECT_NEAR(later, first, 1e-4 * std::max(first, 1.0)) << "face " << i;
    hidden += report.hidden;
  }
  EXPECT_GT(hidden, 0u);
}

// A ray that meets nothing any view shows, last seen rising in front of the sky, reaches it
// although the view at its vanishing point shows a surface: the sky over a parapet behind the
// camera, seen from the front wall, lies in directions in which the camera sees the parapet. The
// parapet (z = -kBack, lit) rises to kParapet above the camera; above it the sky, an environment
// of one colour. The front wall's light is kLit and the sky's colour by their shares of its
// hemisphere; the miss model (--miss frame) takes what the frame does not show for the dark
// wall it shows.
constexpr double kParapet = 2.0;
constexpr float kSkyColour = 0.6f;

WallHit parapet_from(const Imath::V3d& p, const Imath::V3d& d) {
  WallHit w;
  if (d.z > 1e-12) {
    w.t = (kFront - p.z) / d.z;
    w.normal = {0, 0, -1};
  } else if (d.z < -1e-12) {
    const double t = (-kBack - p.z) / d.z;
    if (p.y + t * d.y <= kParapet) {
      w.t = t;
      w.normal = {0, 0, 1};
      w.reflected = kLit;
    }
  }
  return w;
}

TEST(Views, RaysLastSeenRisingInFrontOfTheSkyReachIt) {
  GiSettings s = view_settings();
  s.miss = MissMode::kFrame;
  s.env_color = {kSkyColour, kSkyColour, kSkyColour};
  const Shot shot(s);
  const GBuffer& g = shot.f.g;
  const Image light = light_with_faces(shot, s, parapet_from);
  auto along = [](const Imath::V3d& o, const Imath::V3d& d) {
    const WallHit w = parapet_from(o, d);
    return std::isinf(w.t) ? static_cast<double>(kSkyColour) : static_cast<double>(w.reflected);
  };
  const auto [got, expected] = inner_light_and_expected(g, light, [&](const Imath::V3d& p) {
    return hemisphere_light(p, {0, 0, -1}, along);
  });
  // The share of the front wall's centre's rays that reach the sky in directions in which the
  // camera sees the parapet.
  const double over =
      hemisphere_light({0, 0, kFront}, {0, 0, -1}, [](const Imath::V3d& o, const Imath::V3d& d) {
        return d.z < 0 && std::isinf(parapet_from(o, d).t) && d.y / -d.z * kBack <= kParapet ? 1.0
                                                                                             : 0.0;
      });
  std::printf(
      "six faces: indirect %.4f, expected %.4f (%.0f%% of the front wall's centre's rays "
      "reach the sky over the parapet where the camera sees the parapet)\n",
      got, expected, 100 * over);
  ASSERT_GT(over, 0.1);
  EXPECT_NEAR(got / expected, 1.0, 0.05);
}

// A found ray takes its shares of the miss model out of its sample's (Found::apply): its own
// direction's times its weight, which stand for its run of missed sectors in the mean but can
// exceed what the sample holds on one cube face. The front wall lit, so that the miss model
// (--miss frame) takes what the frame does not show for bright surfaces; every ray of its
// hemisphere meets the back wall in the faces, so its indirect light is the back wall's, kLit,
// and any share left to the miss model would add the front wall's light to it. Holding each
// share at zero instead leaves the undershot faces' shares in place: 1.15 kLit here with two
// rays a slice, 1.28 with one.
TEST(Views, FoundRaysLeaveTheMissModelNothingInTheMean) {
  constexpr float kFrontLight = 2.0f;
  GiSettings s = view_settings();
  s.miss = MissMode::kFrame;
  Shot shot(s);
  GBuffer& g = shot.f.g;
  for (int k = 0; k < 3; ++k)
    for (std::size_t p = 0; p < g.direct.plane_size(); ++p) g.direct.plane(k)[p] = kFrontLight;

  const detail::FrameStages alone(shot.f.seq, s);
  Image coverage;
  const Means without = inner_means(alone.indirect_light(g, &coverage), coverage);
  std::printf("without views: indirect %.4f (the miss model's guess; the back wall's %.4f)\n",
              without.light, kLit);
  ASSERT_GT(without.light, 0.2 * kAlbedo * kFrontLight);

  const detail::FrameStages with(shot.with_views({Projection::kPinhole}), s);
  const detail::LitViews faces = with.light_views(numbered(cube_faces(32), g.frame));
  const Image light = with.indirect_light(g, &coverage, &faces);
  const Means cube = inner_means(light, coverage);
  std::printf("six faces: indirect %.4f (expected %.4f)\n", cube.light, kLit);
  EXPECT_NEAR(cube.light / kLit, 1.0, 0.05);
  // A sample's shares can fall below zero; the light is held at zero.
  for (int k = 0; k < 3; ++k)
    for (std::size_t p = 0; p < light.plane_size(); ++p) ASSERT_GE(light.plane(k)[p], 0.0f);
}

// A closed room around the camera, off its centre, its walls, ceiling and floor all dark but
// the floor, which reflects kFloorLit (y is up, as the cube faces have it). Where a ray from
// point p along d meets the room: its parameter, normal and light.
constexpr double kRoomLow[3] = {-2.0, -1.5, -2.5}, kRoomHigh[3] = {3.0, 1.5, 4.0};
constexpr float kFloorLit = 2.0f;

WallHit room_from(const Imath::V3d& p, const Imath::V3d& d) {
  WallHit w;
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(d[a]) < 1e-12) continue;
    const bool up = d[a] > 0;
    const double t = ((up ? kRoomHigh[a] : kRoomLow[a]) - p[a]) / d[a];
    if (!(t < w.t)) continue;
    w.t = t;
    w.normal = {0, 0, 0};
    w.normal[a] = up ? -1.0 : 1.0;
    w.reflected = a == 1 && !up ? kFloorLit : 0.0f;
  }
  return w;
}

WallHit room(const Imath::V3d& d) { return room_from({0, 0, 0}, d); }

// The one-bounce light at the room's point p with normal n: kFloorLit times the share of its
// cosine-weighted hemisphere that meets the floor.
double floor_share_light(const Imath::V3d& p, const Imath::V3d& n) {
  return hemisphere_light(p, n, [](const Imath::V3d& o, const Imath::V3d& d) {
    return static_cast<double>(room_from(o, d).reflected);
  });
}

// Every face's light with one bounce, against the quadrature at every fourth pixel each way. The
// ceiling's face shows none of the floor: all its rays leave it and are found in the faces below,
// in segments many pixels long. Marched at the default --max-steps samples, it brought 0.91 of
// its light.
TEST(Views, EachFaceOfARoomLitOnItsFloorGetsItsShareOfTheFloor) {
  GiSettings s;  // the defaults' slices, samples and denoising
  s.temporal = TemporalMode::kNone;
  s.bounces = 1;
  const Shot shot(s);
  const detail::FrameStages stages(shot.with_views({Projection::kPinhole}), s);
  constexpr int kSize = 128, kStride = 4;
  const std::vector<GBuffer> faces = numbered(cube_faces(kSize, room), shot.f.g.frame);
  const detail::LitViews lit = stages.light_views(faces);
  ASSERT_EQ(lit.light.size(), faces.size());
  const char* const names[6] = {"forward", "back", "right", "left", "ceiling", "floor"};
  for (std::size_t f = 0; f < faces.size(); ++f) {
    double got = 0, expected = 0;
    for (int y = kStride / 2; y < kSize; y += kStride)
      for (int x = kStride / 2; x < kSize; x += kStride) {
        const Imath::V3d d = world_direction(faces[f].camera, x + 0.5, y + 0.5);
        const WallHit w = room(d);
        expected += floor_share_light(d * w.t, w.normal);
        got += lit.light[f].at(0, x, y);
      }
    const double n = (kSize / kStride) * (kSize / kStride);
    std::printf("%s: light %.4f, expected %.4f\n", names[f], got / n, expected / n);
    if (f == 5)  // the floor sees no floor
      EXPECT_LT(got / n, 0.01 * kFloorLit);
    else
      EXPECT_NEAR(got / expected, 1.0, 0.04) << names[f];
  }
}

// A lat-long's faces are the faces rendered directly, to a pixel's worth of the panorama.
TEST(Views, LatLongFacesAreTheCubeFacesOfItsCamera) {
  Camera ll = latlong_camera(Imath::M44d(), Box2i{0, 0, 1024, 512}, "analytic");
  ll.world_to_camera = Imath::M44d();
  const std::vector<GBuffer> from_ll = detail::latlong_faces(render(ll, 1024, 512), 64);
  const std::vector<GBuffer> direct = cube_faces(64);
  ASSERT_EQ(from_ll.size(), 6u);
  for (int f = 0; f < 6; ++f) {
    const GBuffer &a = from_ll[f], &b = direct[f];
    ASSERT_EQ(a.width(), 64);
    int compared = 0, unlike = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        const float za = a.depth.at(0, x, y), zb = b.depth.at(0, x, y);
        // At the walls' horizon a pixel's nearest panorama pixel may look just past it.
        if (std::isfinite(za) != std::isfinite(zb) || !(zb < 4 * kFront)) {
          unlike += std::isfinite(za) != std::isfinite(zb);
          continue;
        }
        // A lat-long pixel is 0.35 degrees: the depth within a few percent where the walls are
        // seen at a grazing angle.
        EXPECT_NEAR(za / zb, 1.0, 0.05) << "face " << f << " " << x << "," << y;
        for (int k = 0; k < 3; ++k)
          EXPECT_NEAR(a.normal.at(k, x, y), b.normal.at(k, x, y), 1e-5) << "face " << f;
        EXPECT_EQ(a.direct.at(0, x, y), b.direct.at(0, x, y)) << "face " << f;
        ++compared;
      }
    EXPECT_GT(compared, 64 * 64 / 2) << "face " << f;
    EXPECT_LE(unlike, 2 * 64) << "face " << f;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(a.camera.world_to_camera[i][j], b.camera.world_to_camera[i][j], 1e-12)
            << "face " << f;
  }
}

// Where a missed ray passes behind what the frame shows, the slice tracer records (MissedRay::
// hidden), and the views take the ray on from there. The front wall with a bar across the frame
// before it (a band of rows at half its depth): rays from the wall below the bar, heading up
// towards the camera, pass behind the bar's slab and are hidden there; rays that pass in front
// of it leave the frame seen free. A dense walk through the frame's mesh is the judge: at the
// recorded parameter the ray is still free, and after it, before it leaves the frame, it passes
// behind a slab; a ray recorded as never hidden does not.
TEST(Views, MissedRaysKnowWhereTheyPassBehindWhatTheFrameShows) {
  const GiSettings s = view_settings();
  Shot shot(s);
  GBuffer& g = shot.f.g;
  const int w = g.width(), h = g.height();
  for (int y = 2 * h / 5; y < 11 * h / 20; ++y)
    for (int x = 0; x < w; ++x) g.depth.at(0, x, y) = static_cast<float>(kFront / 2);
  const detail::TraceGrid grid =
      detail::make_trace_grid(g, false, 1, static_cast<float>(s.thickness));
  const detail::Environment env;
  const detail::MissModel misses(g, s.miss, env);
  detail::MissedRays missed;
  detail::trace_slices(g, grid, s, misses, &missed);
  const detail::DepthMesh mesh(grid.depth, grid.thickness);

  // Whether camera-space point p lies behind a slab the frame shows; whether ray (o, d) passes
  // such a point after parameter t0, before it leaves the frame.
  auto behind_at = [&](const Imath::V3f& p) {
    if (!(p.z > 0)) return false;
    const float sx = grid.cx + grid.fx * p.x / p.z, sy = grid.cy - grid.fy * p.y / p.z;
    detail::MeshPoint surface;
    return mesh.surface_at(sx, sy, &surface) && p.z > surface.back_z * (1.0f + 1e-4f);
  };
  auto passes_behind = [&](const Imath::V3f& o, const Imath::V3f& d, float t0) {
    const float t_end = d.z < 0 ? 0.999f * o.z / -d.z : 1e3f * o.z;
    constexpr int kSteps = 4000;
    for (int k = 1; k <= kSteps; ++k) {
      const Imath::V3f p = o + (t0 + (t_end - t0) * k / kSteps) * d;
      const float sx = grid.cx + grid.fx * p.x / p.z, sy = grid.cy - grid.fy * p.y / p.z;
      if (!(p.z > 0) || sx < 0 || sy < 0 || sx >= grid.width || sy >= grid.height) return false;
      if (behind_at(p)) return true;
    }
    return false;
  };
  int hidden = 0, free_there = 0, behind_after = 0, seen_free = 0, free_all_along = 0;
  for (std::size_t sample = 0; sample < grid.origin.size(); ++sample) {
    const Imath::V3f& o = missed.origin[sample];
    for (std::uint32_t k = missed.begin[sample]; k < missed.begin[sample + 1]; ++k) {
      const detail::MissedRay& ray = missed.rays[k];
      if (std::isinf(ray.hidden)) {
        ++seen_free;
        free_all_along += !passes_behind(o, ray.direction, 0.0f);
        continue;
      }
      ++hidden;
      free_there += !behind_at(o + ray.hidden * ray.direction);
      behind_after += passes_behind(o, ray.direction, ray.hidden);
    }
  }
  std::printf(
      "%d rays hidden: %d free there, %d pass behind after; %d seen free: %d free all along\n",
      hidden, free_there, behind_after, seen_free, free_all_along);
  ASSERT_GT(hidden, 500);
  ASSERT_GT(seen_free, 500);
  EXPECT_GE(free_there, hidden * 99 / 100);
  EXPECT_GE(behind_after, hidden * 95 / 100);
  EXPECT_GE(free_all_along, seen_free * 95 / 100);
}

}  // namespace
}  // namespace ssgi::pipeline_test
