#include "gi/multiframe.h"

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

// What a trace sample's continued rays found: their light, the environment's light of those
// known to reach the sky, and the shares of the miss model they no longer leave to it (their
// environment light, cube shares and weight).
struct Found {
  float light[3] = {0, 0, 0}, sky[3] = {0, 0, 0}, env[3] = {0, 0, 0}, cube[kCubeFaces] = {};
  float miss = 0;

  // Ray `ray`, found or known to reach the sky, is no longer left to `misses`: its shares of it,
  // as the miss model gives them for its direction.
  void take_shares(const MissModel& misses, const MissedRay& ray) {
    misses.add(ray.direction, ray.weight, env, cube);
    miss += ray.weight;
  }

  // Into sample s: the light added to `foreign`, the shares taken out of `env`, `cube` and
  // `miss`, the sky's light added to `env` (the environment's light, as the misses' is). The
  // tracer summed the shares over its bins of equal angle, and a ray's stand for its whole run
  // of sectors, so they are not exactly what is taken out (kViewRunsPerSlice): with
  // `hold_at_zero`, each share is held at zero, which biases the light up; else only the weight
  // is. (Shrinking all the shares by the found part of the misses instead measured worse: it
  // leaves part of the found direction's share in place, counting that light twice.)
  void apply(std::size_t s, bool hold_at_zero, Image* foreign, Image* env_share, Image* cube_share,
             Image* miss_share) const {
    const float floor = hold_at_zero ? 0.0f : -std::numeric_limits<float>::infinity();
    for (int c = 0; c < 3; ++c) {
      foreign->plane(c)[s] += light[c];
      env_share->plane(c)[s] = std::max(env_share->plane(c)[s] - env[c], floor) + sky[c];
    }
    for (int f = 0; f < kCubeFaces; ++f)
      cube_share->plane(f)[s] = std::max(cube_share->plane(f)[s] - cube[f], floor);
    miss_share->plane(0)[s] = std::max(miss_share->plane(0)[s] - miss, 0.0f);
  }
};

struct Neighbour {
  const View* view;
  Rigid from_center, to_center;
  std::uint32_t index = 0;  // continue_in_views: the view's index among those given
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

// Walks row `by` of `self`'s trace grid: for each missed ray of each sample, `ray_body(s, o, ray,
// jitter, t_from, &found)` with the sample, the rays' camera-space origin, the ray, its march
// jitter and where the frame stops seeing its way free (where the tracer saw it pass behind what
// the frame shows, else where it leaves the frame, or infinite when it never does); then each
// sample's found light and shares go into the four images (Found::apply, `hold_at_zero`).
template <typename RayBody>
void walk_missed_rays(const FrameTrace& self, int by, const GiSettings& settings, bool hold_at_zero,
                      Image* foreign, Image* env, Image* cube, Image* miss,
                      const RayBody& ray_body) {
  const TraceGrid& grid = self.grid;
  for (int bx = 0; bx < grid.width; ++bx) {
    const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
    const std::uint32_t first = self.missed.begin[s], end = self.missed.begin[s + 1];
    if (first == end) continue;
    const Imath::V3f o = self.missed.origin[s];
    Found found;
    for (std::uint32_t k = first; k < end; ++k) {
      const MissedRay& ray = self.missed.rays[k];
      const float jitter = ray_jitter(s, k - first, self.frame, settings.seed);
      const float t_from = std::min(ray.hidden, leaves_view(grid, o, ray.direction, o.z));
      ray_body(s, o, ray, jitter, t_from, &found);
    }
    found.apply(s, hold_at_zero, foreign, env, cube, miss);
  }
}

// A view is walked exactly however long the ray's segment in it: a view's few pixels each span
// much of the scene, so that a segment sampled at --max-steps points steps past surfaces it meets
// steeply (a ceiling's rays to the floor, found in the faces below it, brought 0.91 of the light
// there: Views.EachFaceOfARoomLitOnItsFloorGetsItsShareOfTheFloor), and the walk, which skips
// the empty space of the mesh's bounded quads, is no slower there than the samples
// (BM_IndirectLightWithViews in tests/bench_stages.cpp). The neighbour frames of --multiframe, as
// large as the frame, are sampled as its own march is.
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
bool shows_sky(const std::vector<Neighbour>& views, const Imath::V3f& d) {
  for (const Neighbour& n : views) {
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
  const Neighbour* view = nullptr;  // null: never seen in front of the sky or such a surface
  std::int32_t sample = -1;         // the surface's trace sample, or -1 for the sky
};

// How many pixels out last_seen sets a view's sides to pass over the views that cannot hold a
// point: a point that a grid holds is inside its sides, and the float error of either test, at
// the views' sizes, is far below a pixel, so no view that holds one is passed over.
constexpr float kReachMargin = 1.0f;

// `reach`: each view's sides, kReachMargin out (Frustum), to pass over the views that cannot
// hold a point; `spans`, room for where the ray is inside them. Walks the points from the
// farthest back: the first in front of the sky or of a surface facing the ray is the last seen,
// and a point behind what a view shows found before it tells that the ray was hidden after.
LastSeen last_seen(const std::vector<Neighbour>& views, const std::vector<Frustum>& reach,
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
      const Neighbour& n = views[v];
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

// The centre's hits with the continued rays' light added and their miss shares taken out.
class ContinuedHits final : public HitSource {
 public:
  ContinuedHits(const FrameTrace& t, Image miss, Image env, Image cube, Image foreign)
      : width_(t.grid.width),
        hits_(t.hits),
        miss_(std::move(miss)),
        env_(std::move(env)),
        cube_(std::move(cube)),
        foreign_(std::move(foreign)) {}
  HitRow row(int by, HitScratch*) const override { return hits_.row(by, width_); }
  const Image& miss() const override { return miss_; }
  const Image& env() const override { return env_; }
  const Image& cube() const override { return cube_; }
  const Image* foreign() const override { return &foreign_; }

 private:
  int width_;
  const WeightedHits& hits_;
  Image miss_, env_, cube_, foreign_;
};

}  // namespace

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
  s << "frame " << frame << ": multiframe: ";
  if (frames.empty())
    return s.str() +
           "nothing continued (this frame's camera, or every other frame's in its window, has "
           "no world transform, or theirs are this frame's own)";
  s << rays << " missed rays continued in frames";
  for (int f : frames) s << " " << f;
  s << "; " << found << " met a surface";
  if (moving) s << ", " << moving << " more met only surfaces the frame sees past (not taken)";
  return s.str();
}

std::string ViewsReport::describe(int frame) const {
  std::ostringstream s;
  s << "frame " << frame << ": views: ";
  if (views == 0) return s.str() + "nothing continued (no view has a world transform)";
  s << rays << " missed rays continued in " << views << (views == 1 ? " view" : " views") << "; "
    << found << " met a surface";
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

bool continue_in_views(FrameTrace* self_trace, const std::vector<const FrameTrace*>& views,
                       const std::vector<const Image*>& light, const GiSettings& settings,
                       bool keep_missed, ViewsReport* report, ViewHits* found_rays) {
  FrameTrace& self = *self_trace;
  ViewsReport local;
  ViewsReport& r = report ? *report : local;
  r = ViewsReport();
  if (!self.camera.has_world_transform) return false;
  std::vector<View> all;
  all.reserve(views.size() + 1);
  all.emplace_back(self, nullptr, false, false);  // the frame's own only tells what it sees
  std::vector<Neighbour> neighbours;
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (!views[i]->camera.has_world_transform) continue;
    all.emplace_back(*views[i], settings.bounces > 1 ? light[i] : nullptr, true, true);
    neighbours.push_back({&all.back(), between(self.camera, views[i]->camera),
                          between(views[i]->camera, self.camera), static_cast<std::uint32_t>(i)});
  }
  r.views = static_cast<int>(neighbours.size());
  if (neighbours.empty() || self.missed.rays.empty()) return false;
  const View& own = all.front();
  std::vector<Frustum> frusta, reach;
  for (const Neighbour& n : neighbours) {
    frusta.emplace_back(n.view->trace->grid, n.from_center);
    reach.emplace_back(n.view->trace->grid, n.from_center, kReachMargin);
  }
  const std::size_t count = neighbours.size();
  const TraceGrid& grid = self.grid;
  WeightedHits& hits = self.hits;
  if (hits.foreign.empty()) hits.foreign = Image(grid.width, grid.height, 3);
  // The rays still missed, row by row, for the shot's other frames to continue (multiframe).
  std::vector<std::vector<MissedRay>> row_left(keep_missed ? grid.height : 0);
  std::vector<std::uint32_t> left_count(keep_missed ? grid.origin.size() : 0, 0);
  // The found rays, row by row, when asked for.
  std::vector<std::vector<ViewHit>> found_by_row(found_rays ? grid.height : 0);
  std::vector<std::uint32_t> found_count(found_rays ? grid.origin.size() : 0, 0);
  std::atomic<std::size_t> rays{0}, found{0}, sky{0}, hidden{0}, refused{0};
  struct Entering {
    float t;
    std::size_t n;
  };
  parallel_for_rows(grid.height, [&](int by) {
    std::size_t row_rays = 0, row_found = 0, row_sky = 0, row_hidden = 0, row_refused = 0;
    std::vector<Entering> entering;
    entering.reserve(count);
    // What the rays of one trace sample share, per view: their origin in its space and the
    // values of its frustum's sides there.
    std::size_t sample = ~std::size_t{0};
    std::vector<Imath::V3f> origin_in(count);
    std::vector<std::array<float, 5>> sides_at(count);
    std::vector<std::array<float, 2>> spans;
    const float t_end =
        settings.max_distance > 0 ? static_cast<float>(settings.max_distance) : kFarFactor;
    walk_missed_rays(
        self, by, settings, false, &hits.foreign, &hits.env, &hits.cube, &hits.miss,
        [&](std::size_t s, const Imath::V3f& o, const MissedRay& ray, float jitter, float t_from,
            Found* found_here) {
          // Views at the frame's own time: of the surfaces they show on the ray, the nearest.
          const Neighbour* best = nullptr;
          std::int32_t best_hit = -1;
          float best_along = std::numeric_limits<float>::infinity();
          bool was_refused = false;
          if (!std::isinf(t_from)) {
            ++row_rays;
            // The views the ray passes through, in the order it enters them: a surface a view
            // shows lies within the part of the ray inside its frustum, so once the nearest found
            // is nearer than where the ray enters the next view, that view cannot show a nearer one
            // (the six faces of a cube are each entered after the last is left).
            if (s != sample) {
              sample = s;
              for (std::size_t i = 0; i < count; ++i) {
                origin_in[i] = neighbours[i].from_center.point(o);
                sides_at[i] = frusta[i].at(o, o.z);
              }
            }
            entering.clear();
            const float end = settings.max_distance > 0 ? t_end : t_end * o.z;
            for (std::size_t i = 0; i < count; ++i) {
              const float t_in = frusta[i].enters(sides_at[i], ray.direction, t_from, end);
              if (!std::isinf(t_in)) entering.push_back({t_in, i});
            }
            // By where the ray enters, the views in their given order where that is the same.
            std::sort(entering.begin(), entering.end(), [](const Entering& a, const Entering& b) {
              return a.t < b.t || (a.t == b.t && a.n < b.n);
            });
            for (const Entering& e : entering) {
              if (e.t >= best_along) break;
              const Neighbour& n = neighbours[e.n];
              const Imath::V3f& on = origin_in[e.n];
              const Imath::V3f dn = n.from_center.direction(ray.direction);
              const std::int32_t hit =
                  march_in(*n.view, on, dn, t_from, o.z, jitter, settings, kEveryPixel);
              if (hit < 0) continue;
              const float along = (n.view->vertex(hit_pixel(hit)) - on).dot(dn);
              if (!(along < best_along)) continue;
              if (seen_past(own, n.to_center.point(on + along * dn))) {
                was_refused = true;
                continue;
              }
              best = &n;
              best_hit = hit;
              best_along = along;
            }
          }
          // A view's trace sample `hit` found for the ray: its light (kept with `found_rays`,
          // for the views' later passes among themselves), its shares out of the miss model.
          auto take = [&](const Neighbour& n, std::int32_t hit) {
            add_hit_light(*n.view->trace, n.view->light, hit, ray.weight, found_here->light);
            if (found_rays) {
              found_by_row[by].push_back({n.index, hit, ray.weight});
              ++found_count[s];
            }
            found_here->take_shares(self.misses, ray);
          };
          if (best) {
            take(*best, best_hit);
            ++row_found;
            return;
          }
          // Met nothing any view shows. Where a view shows the sky in its direction it reaches
          // the sky; else it takes what lay behind it where it was last seen: a surface it was
          // heading for, or the sky if it rises (falling, it meets the ground or something on
          // it, which the miss model stands for).
          if (!was_refused && !std::isinf(t_from)) {
            const bool sky_ahead = shows_sky(neighbours, ray.direction);
            const LastSeen seen =
                sky_ahead ? LastSeen()
                          : last_seen(neighbours, reach, o, ray.direction,
                                      static_cast<float>(settings.max_distance), &spans);
            if (sky_ahead ||
                (seen.view && seen.sample < 0 && ray.direction.dot(self.misses.up()) > 0)) {
              found_here->take_shares(self.misses, ray);
              self.misses.add_sky(ray.direction, ray.weight, found_here->sky);
              ++row_sky;
              return;
            }
            if (seen.view && seen.sample >= 0) {
              take(*seen.view, seen.sample);
              ++row_hidden;
              return;
            }
          }
          if (was_refused) ++row_refused;
          if (keep_missed) {
            row_left[by].push_back(ray);
            ++left_count[s];
          }
        });
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
  if (!keep_missed) {
    self.missed = MissedRays();
  } else {
    // The rays left, in trace-sample order.
    MissedRays left;
    left.origin = std::move(self.missed.origin);
    join_rows(
        grid, row_left,
        [&](int by, int bx) { return left_count[static_cast<std::size_t>(by) * grid.width + bx]; },
        &left.begin, &left.rays);
    self.missed = std::move(left);
  }
  if (found_rays)
    join_rows(
        grid, found_by_row,
        [&](int by, int bx) { return found_count[static_cast<std::size_t>(by) * grid.width + bx]; },
        &found_rays->begin, &found_rays->hits);
  return r.found + r.sky + r.hidden > 0;
}

Image view_light(const FrameTrace& self, const ViewHits& found,
                 const std::vector<const FrameTrace*>& views,
                 const std::vector<const Image*>& light, const GiSettings& settings) {
  // Only the views' light tables: the hits are known.
  std::vector<std::vector<std::array<float, 3>>> tables(views.size());
  if (settings.bounces > 1)
    for (std::size_t i = 0; i < views.size(); ++i) tables[i] = hit_light(*views[i], *light[i]);
  const TraceGrid& grid = self.grid;
  Image out(grid.width, grid.height, 3);
  parallel_for_rows(grid.height, [&](int by) {
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      float sum[3] = {0, 0, 0};
      for (std::uint32_t k = found.begin[s]; k < found.begin[s + 1]; ++k) {
        const ViewHit& h = found.hits[k];
        add_hit_light(*views[h.view], tables[h.view], h.hit, h.weight, sum);
      }
      for (int c = 0; c < 3; ++c) out.plane(c)[s] = sum[c];
    }
  });
  return out;
}

bool continue_rays(const std::vector<const FrameTrace*>& frames,
                   const std::vector<const Image*>& light, int center, const GiSettings& settings,
                   Image* out, Image* coverage, Image* shares, ContinuationReport* report) {
  const FrameTrace& self = *frames[center];
  ContinuationReport local;
  ContinuationReport& r = report ? *report : local;
  r = ContinuationReport();
  // The neighbours nearest first (the earlier of two as near), cameras unlike the centre's.
  std::vector<int> order;
  for (int i = 0; i < static_cast<int>(frames.size()); ++i)
    if (i != center && frames[i]->camera.has_world_transform &&
        !same_camera(frames[i]->camera, self.camera))
      order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return std::abs(frames[a]->frame - self.frame) < std::abs(frames[b]->frame - self.frame);
  });
  if (!self.camera.has_world_transform) order.clear();
  for (int i : order) r.frames.push_back(frames[i]->frame);
  if (order.empty() || self.missed.rays.empty()) return false;
  std::vector<View> views;
  views.reserve(order.size() + 1);
  // The centre's own view only tells what it sees: its light is not read.
  views.emplace_back(self, nullptr, false, false);
  std::vector<Neighbour> neighbours;
  for (int i : order) {
    views.emplace_back(*frames[i], settings.bounces > 1 ? light[i] : nullptr, false, true);
    neighbours.push_back({&views.back(), between(self.camera, frames[i]->camera),
                          between(frames[i]->camera, self.camera)});
  }
  const View& own = views.front();
  const TraceGrid& grid = self.grid;
  Image miss = self.hits.miss, env = self.hits.env, cube = self.hits.cube;
  // What the views found (continue_in_views) stays; the neighbours' light adds to it.
  Image foreign = self.hits.foreign.empty() ? Image(grid.width, grid.height, 3) : self.hits.foreign;
  std::atomic<std::size_t> rays{0}, found{0}, moving{0};
  parallel_for_rows(grid.height, [&](int by) {
    std::size_t row_rays = 0, row_found = 0, row_moving = 0;
    // What the found rays no longer leave to the miss model: their shares of it, as the miss
    // model gives them for their directions.
    walk_missed_rays(
        self, by, settings, true, &foreign, &env, &cube, &miss,
        [&](std::size_t, const Imath::V3f& o, const MissedRay& ray, float jitter, float t_from,
            Found* found_here) {
          // The frame has seen the ray's way free up to where it leaves the frame or passes
          // behind something; what lies beyond, the neighbours tell.
          if (std::isinf(t_from)) return;  // free all the way to its vanishing point
          ++row_rays;
          bool refused = false;
          for (const Neighbour& n : neighbours) {
            const Imath::V3f on = n.from_center.point(o);
            const std::int32_t hit = march_in(*n.view, on, n.from_center.direction(ray.direction),
                                              t_from, o.z, jitter, settings, settings.max_steps);
            if (hit < 0) continue;
            const std::int32_t h = hit_pixel(hit);
            // The ray's point nearest the hit vertex: where the hit is, which the centre must
            // not see as empty space.
            const Imath::V3f x = n.view->vertex(h);
            const Imath::V3f dn = n.from_center.direction(ray.direction);
            const float along = (x - on).dot(dn);
            if (seen_past(own, n.to_center.point(on + along * dn))) {
              refused = true;
              continue;
            }
            add_hit_light(*n.view->trace, n.view->light, hit, ray.weight, found_here->light);
            found_here->take_shares(self.misses, ray);
            ++row_found;
            refused = false;
            break;
          }
          if (refused) ++row_moving;
        });
    rays += row_rays;
    found += row_found;
    moving += row_moving;
  });
  r.rays = rays;
  r.found = found;
  r.moving = moving;
  if (r.found == 0) return false;  // nothing changes: no need to gather again
  const ContinuedHits hits(self, std::move(miss), std::move(env), std::move(cube),
                           std::move(foreign));
  *out = gather_bounces(grid, hits, settings.bounces, self.misses, coverage);
  if (shares) *shares = hits.cube();
  return true;
}

}  // namespace ssgi::detail
