#include "gi/continuation.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "gi/march.h"
#include "gi/surface_model.h"
#include "io/camera.h"
#include "parallel.h"

namespace ssgi::detail {
namespace {

// Camera space of one frame to camera space of another, in floats (row vectors:
// p' = p R + t).
struct Rigid {
  Imath::M33f rotation;
  Imath::V3f translation{0, 0, 0};
  Imath::V3f point(const Imath::V3f& p) const { return p * rotation + translation; }
  Imath::V3f direction(const Imath::V3f& d) const { return d * rotation; }
};

// From camera `from`'s space to camera `to`'s (row-vector matrices: from's camera-to-world,
// then to's world-to-camera).
Rigid between(const Camera& from, const Camera& to) {
  const Imath::M44d m = inverse_checked(from.world_to_camera) * to.world_to_camera;
  Rigid out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.rotation[i][j] = static_cast<float>(m[i][j]);
    out.translation[i] = static_cast<float>(m[3][i]);
  }
  return out;
}

// Whether two cameras are one: their world transforms agree to 1e-6 of the larger entry (a
// still camera's matrices written per frame may differ in their last bits).
bool same_camera(const Camera& a, const Camera& b) {
  double largest = 0, difference = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      largest = std::max(
          {largest, std::fabs(a.world_to_camera[i][j]), std::fabs(b.world_to_camera[i][j])});
      difference =
          std::max(difference, std::fabs(a.world_to_camera[i][j] - b.world_to_camera[i][j]));
    }
  return difference <= 1e-6 * largest;
}

// A ray's march jitter in [0, 1): a hash of the trace sample, the ray and the frame (the same
// for any thread count and chunking).
float ray_jitter(std::size_t sample, std::size_t ray, int frame, std::uint32_t seed) {
  return unit_float(
      mix64(mix64(mix64(sample) ^ ray) ^
            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(frame)) << 32 | seed)));
}

// The light a hit on each trace sample of `t` brings (front at 2 s, unseen back at 2 s + 1):
// what it reflects plus its albedo x `own_light`, the indirect light it gathered itself.
std::vector<std::array<float, 3>> hit_light(const FrameTrace& t, const Image& own_light) {
  const TraceGrid& g = t.grid;
  std::vector<std::array<float, 3>> light(2 * g.origin.size());
  parallel_for_rows(g.height, [&](int by) {
    for (int bx = 0; bx < g.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * g.width + bx;
      for (int c = 0; c < 3; ++c) {
        const float back = g.origin[s] < 0 ? 0.0f : g.albedo.plane(c)[s] * own_light.plane(c)[s];
        light[2 * s][c] = g.reflected.plane(c)[s] + back;
        light[2 * s + 1][c] = back;
      }
    }
  });
  return light;
}

// One frame as the continued rays see it: its grid's mesh, its camera, and the light a hit
// on each trace sample brings (front at 2 s, unseen back at 2 s + 1): what it reflects plus its
// albedo x the indirect light the frame gathered itself, after all its bounces (so a continued
// ray brings a bounce more than the frame's own last hits, but for --bounces 1, where it
// brings what the surface reflects alone, and nothing from its back).
struct View {
  const FrameTrace* trace;
  DepthMesh mesh;
  std::vector<std::array<float, 3>> light;

  // `own_light` null: the light of one bounce (what the surfaces reflect, their backs nothing).
  // A view's (`grazing`) mesh also joins neighbours on one plane seen at a grazing angle. Rays
  // are marched in a `marched` one (its mesh bounded); the centre's own is only looked at.
  View(const FrameTrace& t, const Image* own_light, bool grazing, bool marched)
      : trace(&t), mesh(t.grid.depth, t.grid.thickness) {
    const TraceGrid& g = t.grid;
    if (grazing) mesh.join_tangent_neighbours(g.depth, g.normal, g.fx, g.fy, g.cx, g.cy);
    if (marched) mesh.bound_quads();
    if (own_light) light = hit_light(t, *own_light);
  }

  // The camera-space point of trace sample s's vertex.
  Imath::V3f vertex(std::int32_t s) const {
    const TraceGrid& g = trace->grid;
    const float z = g.depth.plane(0)[s];
    const float sx = static_cast<float>(s % g.width) + 0.5f;
    const float sy = static_cast<float>(s / g.width) + 0.5f;
    return {(sx - g.cx) / g.fx * z, (g.cy - sy) / g.fy * z, z};
  }
};

// Adds to `sum` what a ray of `weight` brings from marked hit `hit` on `t`: with its light
// table (hit_light), the front's or the back's light; without (one bounce), what the front
// reflects.
void add_hit_light(const FrameTrace& t, const std::vector<std::array<float, 3>>& light,
                   std::int32_t hit, float weight, float sum[3]) {
  const std::int32_t h = hit_pixel(hit);
  if (light.empty()) {
    if (hit == h)
      for (int c = 0; c < 3; ++c) sum[c] += weight * t.grid.reflected.plane(c)[h];
  } else {
    const std::array<float, 3>& l = light[2 * static_cast<std::size_t>(h) + (hit == h ? 0 : 1)];
    for (int c = 0; c < 3; ++c) sum[c] += weight * l[c];
  }
}

// What a trace sample's continued rays bring: their light, the environment's light of those
// known to reach the sky, and the shares of the miss model they no longer leave to it (their
// environment light, cube shares and weight).
struct ContinuedSample {
  float light[3] = {0, 0, 0}, sky[3] = {0, 0, 0}, env[3] = {0, 0, 0}, cube[kCubeFaces] = {};
  float miss = 0;

  // Ray `ray`, found or known to reach the sky, is no longer left to `misses`: its shares of it,
  // as the miss model gives them for its direction.
  void take_shares(const MissModel& misses, const MissedRay& ray) {
    misses.add(ray.direction, ray.weight, env, cube);
    miss += ray.weight;
  }

  // Into sample s of `shares`: the light added to `continued_light`, the shares taken out of env,
  // cube and miss, the sky's light added to env (the environment's light, as the misses' is). The
  // tracer summed the shares over its bins of equal angle, and a ray's stand for its whole run
  // of sectors, so they are not exactly what is taken out (kViewRunsPerSlice): with
  // `hold_at_zero`, each share is held at zero, which biases the light up; else only the weight
  // is. (Shrinking all the shares by the found part of the misses instead leaves part of the
  // found direction's share in place, counting that light twice.)
  void apply(std::size_t s, bool hold_at_zero, MissShares* shares) const {
    const float floor = hold_at_zero ? 0.0f : -std::numeric_limits<float>::infinity();
    for (int c = 0; c < 3; ++c) {
      shares->continued_light.plane(c)[s] += light[c];
      shares->env.plane(c)[s] = std::max(shares->env.plane(c)[s] - env[c], floor) + sky[c];
    }
    for (int f = 0; f < kCubeFaces; ++f)
      shares->cube.plane(f)[s] = std::max(shares->cube.plane(f)[s] - cube[f], floor);
    shares->miss.plane(0)[s] = std::max(shares->miss.plane(0)[s] - miss, 0.0f);
  }
};

// A source as the frame's rays see it: its view, the rigid motions between the frame's camera
// space and its own, and its index among the sources given.
struct SourceView {
  const View* view;
  Rigid from_center, to_center;
  std::uint32_t index = 0;
};

// Where ray (o, d) (camera space, o inside the view) leaves the view of trace grid `g` (its
// pyramid of sight beyond kNearFraction x `scale`): the infinite float when it never does (its
// vanishing point is in view).
float leaves_view(const TraceGrid& g, const Imath::V3f& o, const Imath::V3f& d, float scale) {
  float t = std::numeric_limits<float>::infinity();
  // Each side as a x p + b >= 0 inside the view.
  auto side = [&](float ax, float ay, float az, float b) {
    const float at = ax * o.x + ay * o.y + az * o.z + b, slope = ax * d.x + ay * d.y + az * d.z;
    if (slope < 0) t = std::min(t, std::max(at, 0.0f) / -slope);
  };
  const float w = static_cast<float>(g.width), h = static_cast<float>(g.height);
  side(g.fx, 0, g.cx, 0);       // sx >= 0
  side(-g.fx, 0, w - g.cx, 0);  // sx <= width
  side(0, -g.fy, g.cy, 0);      // sy >= 0
  side(0, g.fy, h - g.cy, 0);   // sy <= height
  side(0, 0, 1, -kNearFraction * scale);
  return t;
}

// The view of trace grid `g` (its pyramid of sight) as half-spaces of another camera's space,
// `to_view` carrying that space into the view's: side k holds the points p with side[k] . p +
// offset[k] >= 0; side 4, the near plane, also needs kNearFraction x the ray's scale taken off.
// With a `margin`, the four sides stand that many pixels out of the picture.
struct Frustum {
  Imath::V3f side[5];
  float offset[5];

  Frustum(const TraceGrid& g, const Rigid& to_view, float margin = 0) {
    const float w = static_cast<float>(g.width), h = static_cast<float>(g.height);
    // In the view's space (sx >= -margin, sx <= width + margin, sy likewise, z >= 0).
    const Imath::V3f in_view[5] = {{g.fx, 0, g.cx + margin},
                                   {-g.fx, 0, w - g.cx + margin},
                                   {0, -g.fy, g.cy + margin},
                                   {0, g.fy, h - g.cy + margin},
                                   {0, 0, 1}};
    // a . (p R + t) = (R a) . p + a . t (row vectors).
    for (int k = 0; k < 5; ++k) {
      const Imath::V3f& a = in_view[k];
      const Imath::M33f& r = to_view.rotation;
      side[k] = {r[0][0] * a.x + r[0][1] * a.y + r[0][2] * a.z,
                 r[1][0] * a.x + r[1][1] * a.y + r[1][2] * a.z,
                 r[2][0] * a.x + r[2][1] * a.y + r[2][2] * a.z};
      offset[k] = a.dot(to_view.translation);
    }
  }

  // Each side's value at point o (the origin of a trace sample's rays, at depth `scale` in the
  // frame it started from).
  std::array<float, 5> at(const Imath::V3f& o, float scale) const {
    std::array<float, 5> v;
    for (int k = 0; k < 5; ++k) v[k] = side[k].dot(o) + offset[k];
    v[4] -= kNearFraction * scale;
    return v;
  }

  // Where ray (o, d), with its origin's side values `at`, from parameter t_from on, enters the
  // view (up to where march_in ends it, `t_end`): the infinite float when it never does.
  float enters(const std::array<float, 5>& at, const Imath::V3f& d, float t_from,
               float t_end) const {
    float lo = t_from, hi = t_end;
    if (!narrow(at.data(), d, 5, &lo, &hi)) return std::numeric_limits<float>::infinity();
    return lo < hi ? lo : std::numeric_limits<float>::infinity();
  }

  // The parameters [*lo, *hi] of ray (o, d) inside the four sides (which hold only points in
  // front of the camera: two opposite sides' sum is the width times z); false when it passes
  // beside them.
  bool inside_sides(const Imath::V3f& o, const Imath::V3f& d, float* lo, float* hi) const {
    float at[4];
    for (int k = 0; k < 4; ++k) at[k] = side[k].dot(o) + offset[k];
    *lo = -std::numeric_limits<float>::infinity();
    *hi = std::numeric_limits<float>::infinity();
    return narrow(at, d, 4, lo, hi) && *lo <= *hi;
  }

 private:
  // Narrows [*lo, *hi] to the parameters where ray (o, d), with its origin's values `at` of the
  // first `sides` sides, is inside them: false when a side it runs along has it outside.
  bool narrow(const float* at, const Imath::V3f& d, int sides, float* lo, float* hi) const {
    for (int k = 0; k < sides; ++k) {
      const float slope = side[k].dot(d);
      if (slope > 0)
        *lo = std::max(*lo, -at[k] / slope);
      else if (slope < 0)
        *hi = std::min(*hi, at[k] / -slope);
      else if (at[k] < 0)
        return false;
    }
    return true;
  }
};

// ContinuationPolicy::every_pixel: march_in's step count that walks every pixel of a segment.
constexpr int kEveryPixel = std::numeric_limits<int>::max();

// Marches camera-space ray (o, d) of neighbour `n` from parameter t_from on (its origin at depth
// `scale` in the frame it started from) through n's mesh, walking every pixel of a segment up to
// `max_steps` long and sampling a longer one at max_steps points (march_segment): the hit trace
// sample, marked kSeenFromBehind, or -1.
std::int32_t march_in(const View& n, const Imath::V3f& o, const Imath::V3f& d, float t_from,
                      float scale, float jitter, const GiSettings& settings, int max_steps) {
  const TraceGrid& g = n.trace->grid;
  const float near = kNearFraction * scale;
  float t0 = t_from;
  float t1 =
      settings.max_distance > 0 ? static_cast<float>(settings.max_distance) : kFarFactor * scale;
  // Only the part of the ray in front of the camera projects.
  if (o.z + t0 * d.z < near) {
    if (!(d.z > 0)) return -1;
    t0 = (near - o.z) / d.z;
  }
  if (d.z < 0) t1 = std::min(t1, (o.z - near) / -d.z);
  if (!(t1 > t0)) return -1;
  const Imath::V3f a = o + t0 * d;
  const Imath::V3f b = o + t1 * d;
  const float sx0 = g.cx + g.fx * a.x / a.z, sy0 = g.cy - g.fy * a.y / a.z;
  const float sx1 = g.cx + g.fx * b.x / b.z, sy1 = g.cy - g.fy * b.y / b.z;
  ScreenSegment seg{sx0, sy0, sx1 - sx0, sy1 - sy0, 1.0f / a.z, 1.0f / b.z, 0.0f, 1.0f};
  if (!std::isfinite(seg.dx) || !std::isfinite(seg.dy)) return -1;
  if (!clip_to_window(&seg, static_cast<float>(g.width), static_cast<float>(g.height))) return -1;
  // The ray's own surface, where the neighbour shows its origin, is not a hit.
  const bool origin_seen = t0 == 0;
  const int self_x = origin_seen ? static_cast<int>(std::floor(sx0)) : -1;
  const int self_y = origin_seen ? static_cast<int>(std::floor(sy0)) : -1;
  const int hit = march_segment(n.mesh, seg, max_steps, jitter, self_x, self_y);
  if (hit < 0) return -1;
  const Imath::V3f p = n.vertex(hit);
  const float in_front = (o.x - p.x) * g.normal.plane(0)[hit] +
                         (o.y - p.y) * g.normal.plane(1)[hit] +
                         (o.z - p.z) * g.normal.plane(2)[hit];
  return mark_side(hit, in_front < -kBehindTolerance * p.z);
}

// The trace sample of grid `g` under camera-space point (or direction) `q` of its camera: -1 when
// q is not in front of the camera or projects outside the grid.
std::int64_t sample_under(const TraceGrid& g, const Imath::V3f& q) {
  if (!(q.z > 0)) return -1;
  const float sx = g.cx + g.fx * q.x / q.z, sy = g.cy - g.fy * q.y / q.z;
  if (!(sx >= 0 && sy >= 0 && sx < static_cast<float>(g.width) &&
        sy < static_cast<float>(g.height)))
    return -1;
  return static_cast<std::int64_t>(sy) * g.width + static_cast<std::int64_t>(sx);
}

// Whether the views show the sky in camera-space direction `d` (the centre's space): the first
// view (in their order) whose picture holds d's vanishing point shows no surface at the trace
// sample there. What a ray along d meets, if it meets nothing that any view shows, lies beyond
// every surface the views show in its direction: there is none there.
bool shows_sky(const std::vector<SourceView>& views, const Imath::V3f& d) {
  for (const SourceView& n : views) {
    const TraceGrid& g = n.view->trace->grid;
    const std::int64_t i = sample_under(g, n.from_center.direction(d));
    if (i >= 0) return g.origin[i] < 0;
  }
  return false;
}

// Where a ray that meets no surface any view shows was last seen, and in front of what: of
// kLastSeenSamples points along it, at parameters |o| s / (1 - s) for s evenly spaced in (0, 1)
// (denser near its origin, out to 127 times the origin's distance from the camera, and no
// further than `max_distance` when that is set), the last one that the first view holding it
// shows in front of the sky, or in front of a surface facing the ray; provided that the ray
// passed behind what a view shows after it (views that do not cover every direction can lose it
// instead). What the ray meets lies hidden behind that, and is taken to be what lay behind it
// where it was last seen, continued: that surface, which the ray was heading for, or the sky. A
// surface that does not face the ray (its own, a floor it rises from) tells nothing of what the
// ray meets.
constexpr int kLastSeenSamples = 64;

struct LastSeen {
  const SourceView* view = nullptr;  // null: never seen in front of the sky or such a surface
  std::int32_t sample = -1;          // the surface's trace sample, or -1 for the sky
};

// How many pixels out last_seen sets a view's sides to pass over the views that cannot hold a
// point: a point that a grid holds is inside its sides, and the float error of either test, at
// the views' sizes, is far below a pixel, so no view that holds one is passed over.
constexpr float kReachMargin = 1.0f;

// `reach`: each view's sides, kReachMargin out (Frustum), to pass over the views that cannot
// hold a point; `spans`, room for where the ray is inside them. Walks the points from the
// farthest back: the first in front of the sky or of a surface facing the ray is the last seen,
// and a point behind what a view shows found before it tells that the ray was hidden after.
LastSeen last_seen(const std::vector<SourceView>& views, const std::vector<Frustum>& reach,
                   const Imath::V3f& o, const Imath::V3f& d, float max_distance,
                   std::vector<std::array<float, 2>>* spans) {
  const std::size_t count = views.size();
  spans->resize(count);
  bool any = false;
  for (std::size_t v = 0; v < count; ++v) {
    std::array<float, 2>& span = (*spans)[v];
    if (!reach[v].inside_sides(o, d, &span[0], &span[1]))
      span = {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
    else
      any = true;
  }
  if (!any) return LastSeen();
  bool hidden_after = false;
  const float scale = o.length();
  for (int k = kLastSeenSamples - 1; k >= 0; --k) {
    const float s = (static_cast<float>(k) + 0.5f) / kLastSeenSamples;
    const float t = scale * s / (1.0f - s);
    if (max_distance > 0 && t > max_distance) continue;
    const Imath::V3f p = o + t * d;
    for (std::size_t v = 0; v < count; ++v) {
      if (!(t >= (*spans)[v][0] && t <= (*spans)[v][1])) continue;
      const SourceView& n = views[v];
      const TraceGrid& g = n.view->trace->grid;
      const Imath::V3f q = n.from_center.point(p);
      const std::int64_t i = sample_under(g, q);
      if (i < 0) continue;
      if (g.origin[i] < 0) return hidden_after ? LastSeen{&n, -1} : LastSeen();
      if (q.z < g.depth.plane(0)[i]) {
        const Imath::V3f dn = n.from_center.direction(d);
        if (dn.x * g.normal.plane(0)[i] + dn.y * g.normal.plane(1)[i] +
                dn.z * g.normal.plane(2)[i] <
            0)
          return hidden_after ? LastSeen{&n, static_cast<std::int32_t>(i)} : LastSeen();
      } else {
        hidden_after = true;
      }
      break;
    }
  }
  return LastSeen();
}

// Whether the centre frame sees past camera-space point `x` (its own space): x projects onto its
// grid in front of the surface it shows there by more than the slab, or onto its background.
bool seen_past(const View& center, const Imath::V3f& x) {
  const TraceGrid& g = center.trace->grid;
  if (!(x.z > 0)) return false;
  const float sx = g.cx + g.fx * x.x / x.z, sy = g.cy - g.fy * x.y / x.z;
  if (!(sx >= 0 && sy >= 0 && sx < static_cast<float>(g.width) &&
        sy < static_cast<float>(g.height)))
    return false;
  MeshPoint surface;
  if (center.mesh.surface_at(sx, sy, &surface))
    return center.mesh.slab_back(x.z, surface.pixel) < surface.z;
  const float z =
      g.depth.plane(0)[static_cast<std::size_t>(sy) * g.width + static_cast<std::size_t>(sx)];
  return !std::isfinite(z);
}

}  // namespace

ContinuationPolicy continuation_policy(ContinuationPolicy::Kind kind) {
  const bool views = kind == ContinuationPolicy::Kind::kViews;
  ContinuationPolicy p;
  p.kind = kind;
  p.nearest = p.every_pixel = p.join_grazing = p.sky_and_last_seen = views;
  p.hold_shares_at_zero = !views;
  return p;
}

FrameTrace::FrameTrace(int f, const Camera& c, TraceGrid g, WeightedHits h, MissModel m,
                       MissedRays r)
    : frame(f),
      camera(c),
      grid(std::move(g)),
      hits(std::move(h)),
      misses(std::move(m)),
      missed(std::move(r)) {}

void FrameTrace::release_own() {
  hits = WeightedHits();
  missed = MissedRays();
}

std::string ContinuationReport::describe(int frame) const {
  std::ostringstream s;
  s << "frame " << frame;
  if (kind == ContinuationPolicy::Kind::kFrames) {
    s << ": multiframe: ";
    if (sources.empty())
      return s.str() +
             "nothing continued (this frame's camera, or every other frame's in its window, has "
             "no world transform, or theirs are this frame's own)";
    s << rays << " missed rays continued in frames";
    for (int f : sources) s << " " << f;
    s << "; " << found << " met a surface";
  } else {
    s << ": views: ";
    if (sources.empty()) return s.str() + "nothing continued (no view has a world transform)";
    s << rays << " missed rays continued in " << sources.size()
      << (sources.size() == 1 ? " view" : " views") << "; " << found << " met a surface";
  }
  if (sky)
    s << ", " << sky
      << " reached the sky (the views show it in their direction, or where they were last seen "
         "rising)";
  if (hidden)
    s << ", " << hidden
      << " passed behind what the views show and take the surface they were last seen heading for";
  if (refused) s << ", " << refused << " more met only surfaces the frame sees past (not taken)";
  return s.str();
}

Continuation continue_missed_rays(const FrameTrace& self, MissShares shares,
                                  const std::vector<ContinuationSource>& given,
                                  const ContinuationPolicy& policy, const GiSettings& settings,
                                  bool keep_missed, bool record_found) {
  Continuation out;
  ContinuationReport& r = out.report;
  r.kind = policy.kind;
  out.shares = std::move(shares);
  if (!self.camera.has_world_transform) return out;
  std::vector<View> views;
  views.reserve(given.size() + 1);
  // The frame's own only tells what it sees: its light is not read, nor its mesh marched.
  views.emplace_back(self, nullptr, false, false);
  std::vector<SourceView> sources;
  for (std::size_t i = 0; i < given.size(); ++i) {
    const FrameTrace& t = *given[i].trace;
    if (!t.camera.has_world_transform) continue;
    views.emplace_back(t, settings.bounces > 1 ? given[i].light : nullptr, policy.join_grazing,
                       true);
    sources.push_back({&views.back(), between(self.camera, t.camera),
                       between(t.camera, self.camera), static_cast<std::uint32_t>(i)});
    r.sources.push_back(t.frame);
  }
  if (sources.empty() || self.missed.rays.empty()) return out;
  out.walked = true;
  const View& own = views.front();
  const std::size_t count = sources.size();
  // The nearest surface: where the ray enters each source's view, and for the sky and last-seen
  // rules, each view's sides a margin out.
  std::vector<Frustum> frusta, reach;
  if (policy.nearest || policy.sky_and_last_seen)
    for (const SourceView& n : sources) {
      frusta.emplace_back(n.view->trace->grid, n.from_center);
      reach.emplace_back(n.view->trace->grid, n.from_center, kReachMargin);
    }
  const int max_steps = policy.every_pixel ? kEveryPixel : settings.max_steps;
  const TraceGrid& grid = self.grid;
  MissShares& into = out.shares;
  if (into.continued_light.empty()) into.continued_light = Image(grid.width, grid.height, 3);
  // The rays still missed, and the found rays, row by row.
  std::vector<std::vector<MissedRay>> row_left(keep_missed ? grid.height : 0);
  std::vector<std::uint32_t> left_count(keep_missed ? grid.origin.size() : 0, 0);
  std::vector<std::vector<SourceHit>> found_by_row(record_found ? grid.height : 0);
  std::vector<std::uint32_t> found_count(record_found ? grid.origin.size() : 0, 0);
  std::atomic<std::size_t> rays{0}, found{0}, sky{0}, hidden{0}, refused{0};
  struct Entering {
    float t;
    std::size_t n;
  };
  const float t_end =
      settings.max_distance > 0 ? static_cast<float>(settings.max_distance) : kFarFactor;
  parallel_for_rows(grid.height, [&](int by) {
    std::size_t row_rays = 0, row_found = 0, row_sky = 0, row_hidden = 0, row_refused = 0;
    std::vector<Entering> entering;
    entering.reserve(count);
    // What the rays of one trace sample share, per source: their origin in its space and the
    // values of its frustum's sides there.
    std::vector<Imath::V3f> origin_in(count);
    std::vector<std::array<float, 5>> sides_at(policy.nearest ? count : 0);
    std::vector<std::array<float, 2>> spans;
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      const std::uint32_t first = self.missed.begin[s], end = self.missed.begin[s + 1];
      if (first == end) continue;
      const Imath::V3f o = self.missed.origin[s];
      bool placed = false;  // origin_in and sides_at hold this sample's, once a ray needs them
      ContinuedSample sample;
      for (std::uint32_t k = first; k < end; ++k) {
        const MissedRay& ray = self.missed.rays[k];
        // The frame has seen the ray's way free up to where it leaves the frame or passes
        // behind something; what lies beyond, the sources tell.
        const float t_from = std::min(ray.hidden, leaves_view(grid, o, ray.direction, o.z));
        if (std::isinf(t_from)) {  // free all the way to its vanishing point
          if (keep_missed) {
            row_left[by].push_back(ray);
            ++left_count[s];
          }
          continue;
        }
        ++row_rays;
        if (!placed) {
          for (std::size_t i = 0; i < count; ++i) {
            origin_in[i] = sources[i].from_center.point(o);
            if (policy.nearest) sides_at[i] = frusta[i].at(o, o.z);
          }
          placed = true;
        }
        const float jitter = ray_jitter(s, k - first, self.frame, settings.seed);
        // The sources to march in: with `nearest`, those the ray passes through, in the order it
        // enters them: a surface a view shows lies within the part of the ray inside its
        // frustum, so once the nearest found is nearer than where the ray enters the next view,
        // that view cannot show a nearer one (the six faces of a cube are each entered after
        // the last is left); else all, in their order, until one shows a surface.
        entering.clear();
        if (policy.nearest) {
          const float ray_end = settings.max_distance > 0 ? t_end : t_end * o.z;
          for (std::size_t i = 0; i < count; ++i) {
            const float t_in = frusta[i].enters(sides_at[i], ray.direction, t_from, ray_end);
            if (!std::isinf(t_in)) entering.push_back({t_in, i});
          }
          // By where the ray enters, the sources in their given order where that is the same.
          std::sort(entering.begin(), entering.end(), [](const Entering& a, const Entering& b) {
            return a.t < b.t || (a.t == b.t && a.n < b.n);
          });
        } else {
          for (std::size_t i = 0; i < count; ++i) entering.push_back({t_from, i});
        }
        const SourceView* best = nullptr;
        std::int32_t best_hit = -1;
        float best_along = std::numeric_limits<float>::infinity();
        bool was_refused = false;
        for (const Entering& e : entering) {
          if (policy.nearest && e.t >= best_along) break;
          const SourceView& n = sources[e.n];
          const Imath::V3f& on = origin_in[e.n];
          const Imath::V3f dn = n.from_center.direction(ray.direction);
          const std::int32_t hit =
              march_in(*n.view, on, dn, t_from, o.z, jitter, settings, max_steps);
          if (hit < 0) continue;
          // The ray's point nearest the hit vertex: where the hit is, which the frame must not
          // see as empty space.
          const float along = (n.view->vertex(hit_pixel(hit)) - on).dot(dn);
          if (policy.nearest && !(along < best_along)) continue;
          if (seen_past(own, n.to_center.point(on + along * dn))) {
            was_refused = true;
            continue;
          }
          best = &n;
          best_hit = hit;
          best_along = along;
          if (!policy.nearest) break;
        }
        // A source's trace sample `hit` found for the ray: its light, its shares out of the
        // miss model.
        auto take = [&](const SourceView& n, std::int32_t hit) {
          add_hit_light(*n.view->trace, n.view->light, hit, ray.weight, sample.light);
          if (record_found) {
            found_by_row[by].push_back({n.index, hit, ray.weight});
            ++found_count[s];
          }
          sample.take_shares(self.misses, ray);
        };
        if (best) {
          take(*best, best_hit);
          ++row_found;
          continue;
        }
        // Met nothing any view shows. Where a view shows the sky in its direction it reaches
        // the sky; else it takes what lay behind it where it was last seen: a surface it was
        // heading for, or the sky if it rises (falling, it meets the ground or something on
        // it, which the miss model stands for).
        if (policy.sky_and_last_seen && !was_refused) {
          const bool sky_ahead = shows_sky(sources, ray.direction);
          const LastSeen seen = sky_ahead
                                    ? LastSeen()
                                    : last_seen(sources, reach, o, ray.direction,
                                                static_cast<float>(settings.max_distance), &spans);
          if (sky_ahead ||
              (seen.view && seen.sample < 0 && ray.direction.dot(self.misses.up()) > 0)) {
            sample.take_shares(self.misses, ray);
            self.misses.add_sky(ray.direction, ray.weight, sample.sky);
            ++row_sky;
            continue;
          }
          if (seen.view && seen.sample >= 0) {
            take(*seen.view, seen.sample);
            ++row_hidden;
            continue;
          }
        }
        if (was_refused) ++row_refused;
        if (keep_missed) {
          row_left[by].push_back(ray);
          ++left_count[s];
        }
      }
      sample.apply(s, policy.hold_shares_at_zero, &into);
    }
    rays += row_rays;
    found += row_found;
    sky += row_sky;
    hidden += row_hidden;
    refused += row_refused;
  });
  r.rays = rays;
  r.found = found;
  r.sky = sky;
  r.hidden = hidden;
  r.refused = refused;
  if (keep_missed) {
    // The rays left, in trace-sample order.
    join_rows(
        grid, row_left,
        [&](int by, int bx) { return left_count[static_cast<std::size_t>(by) * grid.width + bx]; },
        &out.left.begin, &out.left.rays);
  }
  if (record_found)
    join_rows(
        grid, found_by_row,
        [&](int by, int bx) { return found_count[static_cast<std::size_t>(by) * grid.width + bx]; },
        &out.found.begin, &out.found.hits);
  return out;
}

Continuation continue_into(FrameTrace* t, const std::vector<ContinuationSource>& sources,
                           const ContinuationPolicy& policy, const GiSettings& settings,
                           bool keep_missed, bool record_found) {
  Continuation c = continue_missed_rays(*t, take_shares(&t->hits), sources, policy, settings,
                                        keep_missed, record_found);
  put_shares(std::move(c.shares), &t->hits);
  if (c.walked) {
    if (keep_missed) c.left.origin = std::move(t->missed.origin);
    t->missed = std::move(c.left);
  }
  return c;
}

Image source_light(const FrameTrace& self, const SourceHits& found,
                   const std::vector<ContinuationSource>& sources, const GiSettings& settings) {
  // Only the sources' light tables: the hits are known.
  std::vector<std::vector<std::array<float, 3>>> tables(sources.size());
  if (settings.bounces > 1)
    for (std::size_t i = 0; i < sources.size(); ++i)
      tables[i] = hit_light(*sources[i].trace, *sources[i].light);
  const TraceGrid& grid = self.grid;
  Image out(grid.width, grid.height, 3);
  parallel_for_rows(grid.height, [&](int by) {
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      float sum[3] = {0, 0, 0};
      for (std::uint32_t k = found.begin[s]; k < found.begin[s + 1]; ++k) {
        const SourceHit& h = found.hits[k];
        add_hit_light(*sources[h.source].trace, tables[h.source], h.hit, h.weight, sum);
      }
      for (int c = 0; c < 3; ++c) out.plane(c)[s] = sum[c];
    }
  });
  return out;
}

std::vector<ContinuationSource> window_sources(const std::vector<const FrameTrace*>& frames,
                                               const std::vector<const Image*>& light, int center) {
  const FrameTrace& self = *frames[center];
  std::vector<int> order;
  if (self.camera.has_world_transform)
    for (int i = 0; i < static_cast<int>(frames.size()); ++i)
      if (i != center && frames[i]->camera.has_world_transform &&
          !same_camera(frames[i]->camera, self.camera))
        order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return std::abs(frames[a]->frame - self.frame) < std::abs(frames[b]->frame - self.frame);
  });
  std::vector<ContinuationSource> out;
  for (int i : order) out.push_back({frames[i], light[i]});
  return out;
}

}  // namespace ssgi::detail
