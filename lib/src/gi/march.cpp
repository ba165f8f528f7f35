#include "gi/march.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gi/directions.h"
#include "gi/surface_model.h"
#include "parallel.h"

namespace ssgi::detail {
namespace {

// Samples the segment at `steps` evenly spaced, jittered points: a sample hits when it is
// inside a slab, or when the ray passed the front of one continuous surface since the last
// sample. Approximate (it can step over a thin slab or hit a pixel late); used when the ray
// is longer than the step budget. On a bounded mesh a sample in front of its whole quad
// (DepthMesh::in_front_at) is known not to hit, and its surface is looked up only when the
// next sample asks whether the ray passed it.
int march_sampled(const DepthMesh& mesh, const ScreenSegment& s, int steps, float jitter,
                  int self_x, int self_y) {
  const float df = (s.f_hi - s.f_lo) / steps;
  const float inf = std::numeric_limits<float>::infinity();
  bool prev_valid = false, prev_in_front = false, prev_deferred = false;
  float prev_z = 0.0f, prev_x = 0.0f, prev_y = 0.0f;
  int prev_pixel = 0;
  for (int i = 0; i < steps; ++i) {
    const float f = s.f_lo + df * (i + jitter);
    const float sx = s.sx0 + s.dx * f, sy = s.sy0 + s.dy * f;
    if (static_cast<int>(std::floor(sx)) == self_x && static_cast<int>(std::floor(sy)) == self_y)
      continue;
    const float hr = s.h0 + (s.h1 - s.h0) * f;
    bool covered;
    if (mesh.in_front_at(sx, sy, hr, &covered)) {
      prev_valid = covered;
      prev_in_front = true;
      prev_deferred = true;
      prev_x = sx, prev_y = sy;
      continue;
    }
    MeshPoint surface;
    if (!mesh.surface_at(sx, sy, &surface)) {
      prev_valid = false;
      continue;
    }
    const float z_ray = hr > 0 ? 1.0f / hr : inf;
    const bool behind_front = z_ray >= surface.z;
    if (behind_front && prev_valid && prev_in_front && prev_deferred) {
      MeshPoint before;
      mesh.surface_at(prev_x, prev_y, &before);
      prev_z = before.z;
      prev_pixel = before.pixel;
    }
    if (behind_front &&
        (z_ray <= surface.back_z || (prev_valid && prev_in_front &&
                                     mesh.connected(prev_z, prev_pixel, surface.z, surface.pixel))))
      return surface.pixel;
    prev_valid = true;
    prev_in_front = !behind_front;
    prev_deferred = false;
    prev_z = surface.z;
    prev_pixel = surface.pixel;
  }
  return -1;
}

// The part [*lo, *hi] of the segment inside the box [x0, x1] x [y0, y1] (Liang-Barsky);
// leaves them unchanged when the segment misses the box.
void clip_to_box(const ScreenSegment& s, float x0, float y0, float x1, float y1, float* lo,
                 float* hi) {
  float a = -std::numeric_limits<float>::infinity(), b = std::numeric_limits<float>::infinity();
  auto clip = [&](float p, float q) {
    if (p == 0) return q >= 0;
    const float r = q / p;
    if (p < 0) {
      if (r > b) return false;
      a = std::max(a, r);
    } else {
      if (r < a) return false;
      b = std::min(b, r);
    }
    return true;
  };
  if (clip(-s.dx, s.sx0 - x0) && clip(s.dx, x1 - s.sx0) && clip(-s.dy, s.sy0 - y0) &&
      clip(s.dy, y1 - s.sy0) && a <= b) {
    *lo = a;
    *hi = b;
  }
}

// Walks every mesh triangle the segment crosses, in order (a 2-D DDA over the quads of pixel
// centres, each split at its diagonal), and solves exactly where the ray is inside the
// triangle's slab: within one triangle the ray's and the surface's inverse depths are both
// affine in f, so "behind the front, before the back" is an interval. The first point of it
// outside the ray's own pixel is the hit. This is the surface model itself, which the Embree
// reference traces too. On a bounded mesh the walk goes tile by tile first, and walks the
// quads of a tile only where the ray may meet a slab in it (DepthMesh::tile_clear_of), and
// skips the quads it cannot meet one in (clear_of).
class ExactWalk {
 public:
  ExactWalk(const DepthMesh& mesh, const ScreenSegment& s, int self_x, int self_y)
      : mesh_(mesh), s_(s), u0_(s.sx0 - 0.5f), v0_(s.sy0 - 0.5f) {
    if (self_x >= 0 && self_y >= 0)
      clip_to_box(s, self_x, self_y, self_x + 1.0f, self_y + 1.0f, &own_lo_, &own_hi_);
    past_own_ = kPastEdgePx / std::max(std::fabs(s.dx), std::fabs(s.dy));
  }

  int run() const {
    if (!mesh_.bounded()) return quads(s_.f_lo, s_.f_hi);
    const float tile = static_cast<float>(DepthMesh::kTile);
    return dda(s_.f_lo, s_.f_hi, tile, 2 * (mesh_.width() + mesh_.height()) / DepthMesh::kTile + 4,
               [&](int ti, int tj, float fa, float fb) {
                 return mesh_.tile_clear_of(ti, tj, inverse_depth(fa), inverse_depth(fb))
                            ? -1
                            : quads(fa, fb);
               });
  }

 private:
  float inverse_depth(float f) const { return s_.h0 + (s_.h1 - s_.h0) * f; }

  // Calls visit(i, j, fa, fb) for each cell (i, j) of a lattice of `size` units (of pixel
  // centres) the segment crosses for f in [from, to], in order, with the part [fa, fb] in it,
  // until it returns a hit (>= 0); that hit, or -1.
  template <typename Visit>
  int dda(float from, float to, float size, int max_cells, const Visit& visit) const {
    const float inf = std::numeric_limits<float>::infinity();
    int i = static_cast<int>(std::floor((u0_ + s_.dx * from) / size));
    int j = static_cast<int>(std::floor((v0_ + s_.dy * from) / size));
    const int step_i = s_.dx > 0 ? 1 : -1, step_j = s_.dy > 0 ? 1 : -1;
    float next_u = s_.dx != 0 ? ((step_i > 0 ? i + 1 : i) * size - u0_) / s_.dx : inf;
    float next_v = s_.dy != 0 ? ((step_j > 0 ? j + 1 : j) * size - v0_) / s_.dy : inf;
    const float delta_u = s_.dx != 0 ? size / std::fabs(s_.dx) : inf;
    const float delta_v = s_.dy != 0 ? size / std::fabs(s_.dy) : inf;
    float f = from;
    for (int cell = 0; cell < max_cells && f < to; ++cell) {
      const float fe = std::min(std::min(next_u, next_v), to);
      if (fe > f) {
        const int hit = visit(i, j, f, fe);
        if (hit >= 0) return hit;
        f = fe;
      }
      if (next_u < next_v) {
        i += step_i;
        next_u += delta_u;
      } else {
        j += step_j;
        next_v += delta_v;
      }
    }
    return -1;
  }

  // The first hit for f in [from, to], quad by quad.
  int quads(float from, float to) const {
    return dda(from, to, 1.0f, 2 * (mesh_.width() + mesh_.height()) + 4,
               [&](int i, int j, float f, float fe) {
                 if (mesh_.clear_of(i, j, inverse_depth(f), inverse_depth(fe))) return -1;
                 // The diagonal (i, j)-(i+1, j+1), where u - i = v - j, splits the quad in two.
                 const float fd =
                     s_.dx != s_.dy
                         ? ((static_cast<float>(i) - u0_) - (static_cast<float>(j) - v0_)) /
                               (s_.dx - s_.dy)
                         : std::numeric_limits<float>::infinity();
                 if (!(fd > f && fd < fe)) return piece(i, j, f, fe);
                 const int hit = piece(i, j, f, fd);
                 return hit >= 0 ? hit : piece(i, j, fd, fe);
               });
  }

  // The first point of [fa, fb] inside the slab of the triangle of quad (i, j) it lies in.
  int piece(int i, int j, float fa, float fb) const {
    if (!(fb > fa)) return -1;
    const ScreenSegment& s = s_;
    const float u0 = u0_, v0 = v0_;
    const float fm = 0.5f * (fa + fb);
    const bool upper = (u0 + s.dx * fm - i) >= (v0 + s.dy * fm - j);
    if (!mesh_.has_triangle(i, j, upper)) return -1;
    const float surf_a =
        mesh_.inverse_depth_at(i, j, upper, u0 + s.dx * fa - i, v0 + s.dy * fa - j);
    const float surf_b =
        mesh_.inverse_depth_at(i, j, upper, u0 + s.dx * fb - i, v0 + s.dy * fb - j);
    const float back_a = mesh_.inverse_back_at(i, j, upper, u0 + s.dx * fa - i, v0 + s.dy * fa - j);
    const float back_b = mesh_.inverse_back_at(i, j, upper, u0 + s.dx * fb - i, v0 + s.dy * fb - j);
    const float ray_a = inverse_depth(fa), ray_b = inverse_depth(fb);
    float lo = fa, hi = fb;
    // Keeps the part of [lo, hi] where the affine r (ra at fa, rb at fb) is >= 0.
    auto keep_non_negative = [&](float ra, float rb) {
      if (ra >= 0 && rb >= 0) return true;
      if (ra < 0 && rb < 0) return false;
      const float fr = fa + (fb - fa) * (ra / (ra - rb));
      if (ra >= 0)
        hi = std::min(hi, fr);
      else
        lo = std::max(lo, fr);
      return lo <= hi;
    };
    // Behind the front (1/z_ray <= 1/z_surface), before the back (1/z_ray >= 1/z_back).
    if (!keep_non_negative(surf_a - ray_a, surf_b - ray_b) ||
        !keep_non_negative(ray_a - back_a, ray_b - back_b))
      return -1;
    float f = lo;
    if (f >= own_lo_ && f <= own_hi_) {
      f = own_hi_ + past_own_;
      if (f > hi) return -1;
    }
    return mesh_.heaviest_vertex(i, j, upper, u0 + s.dx * f - i, v0 + s.dy * f - j);
  }

  const DepthMesh& mesh_;
  const ScreenSegment& s_;
  float u0_, v0_;  // the segment's start on the lattice of pixel centres
  // Where the segment is inside its own pixel, and how far past it a hit is taken.
  float own_lo_ = 2.0f, own_hi_ = 2.0f, past_own_;
};

}  // namespace

bool clip_to_window(ScreenSegment* s, float width, float height) {
  auto clip = [&](float p, float q) {
    if (p == 0) return q >= 0;
    const float r = q / p;
    if (p < 0) {
      if (r > s->f_hi) return false;
      s->f_lo = std::max(s->f_lo, r);
    } else {
      if (r < s->f_lo) return false;
      s->f_hi = std::min(s->f_hi, r);
    }
    return true;
  };
  return clip(-s->dx, s->sx0) && clip(s->dx, width - s->sx0) && clip(-s->dy, s->sy0) &&
         clip(s->dy, height - s->sy0) && s->f_hi > s->f_lo;
}

int march_segment(const DepthMesh& mesh, const ScreenSegment& s, int max_steps, float jitter,
                  int self_x, int self_y) {
  const float length_px = std::max(std::fabs(s.dx), std::fabs(s.dy)) * (s.f_hi - s.f_lo);
  return length_px <= static_cast<float>(max_steps)
             ? ExactWalk(mesh, s, self_x, self_y).run()
             : march_sampled(mesh, s, max_steps, jitter, self_x, self_y);
}

namespace {

struct Tracer {
  const GBuffer& g;
  const GiSettings& settings;
  SurfaceModel model;
  DepthMesh mesh;
  int width, height;
  int offset_x, offset_y;  // data window origin in display-window pixels

  Tracer(const GBuffer& gb, const GiSettings& s)
      : g(gb),
        settings(s),
        model{static_cast<float>(s.thickness)},
        mesh(gb.depth, feature_thickness(gb, model)),
        width(gb.width()),
        height(gb.height()),
        offset_x(gb.data_window.x0 - gb.display_window.x0),
        offset_y(gb.data_window.y0 - gb.display_window.y0) {}

  // Marches one ray from camera-space origin `o` along unit `d`; returns the index of the
  // pixel whose light it brings (marked as surface_model.h says when seen from behind), or -1. The
  // ray is projected to the screen and sampled at up to max_steps evenly spaced, jittered points
  // (one per pixel along the major axis when steps allow); its depth is interpolated
  // perspective-correctly (1/z is linear in screen space, McGuire & Mara 2014) and tested against
  // the mesh of surface_model.h.
  int march_ray(const Imath::V3f& o, const Imath::V3f& d, float jitter, int self_x,
                int self_y) const {
    float t_end =
        settings.max_distance > 0 ? static_cast<float>(settings.max_distance) : kFarFactor * o.z;
    if (d.z < 0) t_end = std::min(t_end, (o.z - kNearFraction * o.z) / -d.z);
    if (!(t_end > 0)) return -1;
    const Imath::V3f e = o + t_end * d;
    const Camera& cam = g.camera;
    // Screen positions in data-window pixel units.
    const float sx0 = static_cast<float>(cam.cx + cam.fx * o.x / o.z) - offset_x;
    const float sy0 = static_cast<float>(cam.cy - cam.fy * o.y / o.z) - offset_y;
    const float sx1 = static_cast<float>(cam.cx + cam.fx * e.x / e.z) - offset_x;
    const float sy1 = static_cast<float>(cam.cy - cam.fy * e.y / e.z) - offset_y;
    const float h0 = 1.0f / o.z, h1 = 1.0f / e.z;
    const float dx = sx1 - sx0, dy = sy1 - sy0;
    if (!std::isfinite(dx) || !std::isfinite(dy)) return -1;

    // Clip the screen segment to the data window (Liang-Barsky); beyond it is a miss.
    ScreenSegment seg{sx0, sy0, dx, dy, h0, h1, 0.0f, 1.0f};
    if (!clip_to_window(&seg, static_cast<float>(width), static_cast<float>(height))) return -1;
    const bool leaves_screen = seg.f_hi < 1.0f;
    const int hit = march_segment(mesh, seg, settings.max_steps, jitter, self_x, self_y);
    if (hit >= 0) return hit;
    if (leaves_screen && settings.miss == MissMode::kExtend)
      return extend_edge(o, d, sx0 + dx * seg.f_hi, sy0 + dy * seg.f_hi);
    return -1;
  }

  // MissMode::kExtend: the surface at the pixel where the ray leaves the screen continues as
  // its tangent plane beyond the edge; a ray that meets that plane from its front side takes
  // the edge pixel's light. Returns the edge pixel's index, or -1.
  int extend_edge(const Imath::V3f& o, const Imath::V3f& d, float exit_x, float exit_y) const {
    const int ix = std::clamp(static_cast<int>(std::floor(exit_x)), 0, width - 1);
    const int iy = std::clamp(static_cast<int>(std::floor(exit_y)), 0, height - 1);
    const float ze = g.depth.at(0, ix, iy);
    if (!std::isfinite(ze)) return -1;
    const Imath::V3f n{g.normal.at(0, ix, iy), g.normal.at(1, ix, iy), g.normal.at(2, ix, iy)};
    const Imath::V3d pe = g.camera.unproject(ix + offset_x + 0.5, iy + offset_y + 0.5, ze);
    const float facing = n.dot(d);
    if (!(facing < 0)) return -1;
    const float t =
        (n.x * (static_cast<float>(pe.x) - o.x) + n.y * (static_cast<float>(pe.y) - o.y) +
         n.z * (static_cast<float>(pe.z) - o.z)) /
        facing;
    if (!(t > 0) || (settings.max_distance > 0 && t > settings.max_distance)) return -1;
    return iy * width + ix;
  }

  // Calls on_ray(k, hit_index, direction) for each ray of surface pixel (x, y), hits marked as
  // mark_hit says.
  template <typename OnRay>
  void trace_pixel(int x, int y, const OnRay& on_ray) const {
    const PixelRays rays(g, settings, x, y);
    for (int k = 0; k < settings.rays; ++k) {
      float jitter;
      const Imath::V3f d = rays.direction(k, &jitter);
      const int hit = march_ray(rays.origin(), d, jitter, x, y);
      on_ray(k, hit >= 0 ? mark_hit(g, hit, rays.origin()) : hit, d);
    }
  }
};

}  // namespace

std::int32_t mark_hit(const GBuffer& g, std::int32_t hit, const Imath::V3f& origin) {
  const int x = hit % g.width(), y = hit / g.width();
  const Imath::V3d p =
      g.camera.unproject(x + g.data_window.x0 - g.display_window.x0 + 0.5,
                         y + g.data_window.y0 - g.display_window.y0 + 0.5, g.depth.plane(0)[hit]);
  const double in_front = (origin.x - p.x) * g.normal.plane(0)[hit] +
                          (origin.y - p.y) * g.normal.plane(1)[hit] +
                          (origin.z - p.z) * g.normal.plane(2)[hit];
  return mark_side(hit, in_front < -kBehindTolerance * p.z);
}

PixelRays::PixelRays(const GBuffer& g, const GiSettings& settings, int x, int y) {
  const int px = x + g.data_window.x0 - g.display_window.x0;
  const int py = y + g.data_window.y0 - g.display_window.y0;
  const float z = g.depth.at(0, x, y);
  const Imath::V3d p = g.camera.unproject(px + 0.5, py + 0.5, z);
  normal_ = {g.normal.at(0, x, y), g.normal.at(1, x, y), g.normal.at(2, x, y)};
  const float off = static_cast<float>(settings.start_offset) * z;
  origin_ = {static_cast<float>(p.x) + normal_.x * off, static_cast<float>(p.y) + normal_.y * off,
             static_cast<float>(p.z) + normal_.z * off};
  noise_ = pixel_noise(px, py, g.frame, settings.seed);
}

Imath::V3f PixelRays::direction(int k, float* jitter) const {
  float u1, u2;
  ray_sample(noise_, k, &u1, &u2, jitter);
  return cosine_hemisphere(normal_, u1, u2);
}

RayHits::RayHits(const GBuffer& g, int n)
    : rays(n),
      hit(static_cast<std::size_t>(g.width()) * g.height() * n, -1),
      env_sum(g.width(), g.height(), 3),
      cube_sum(g.width(), g.height(), kCubeFaces),
      miss_count(g.width(), g.height(), 1) {}

void RayHits::store_misses(std::size_t p, int count, const float env[3],
                           const float cube[kCubeFaces]) {
  miss_count.plane(0)[p] = static_cast<float>(count);
  for (int c = 0; c < 3; ++c) env_sum.plane(c)[p] = env[c];
  for (int f = 0; f < kCubeFaces; ++f) cube_sum.plane(f)[p] = cube[f];
}

RayHits march_screen_space(const GBuffer& g, const GiSettings& settings, const MissModel& misses) {
  const Tracer tracer(g, settings);
  const int w = g.width(), h = g.height(), rays = settings.rays;
  RayHits hits(g, rays);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      std::int32_t* out = &hits.hit[p * rays];
      float env[3] = {0, 0, 0}, cube[kCubeFaces] = {0, 0, 0, 0, 0, 0};
      int missed = 0;
      tracer.trace_pixel(x, y, [&](int k, int hit, const Imath::V3f& d) {
        out[k] = hit;
        if (hit >= 0) return;
        ++missed;
        misses.add(d, 1.0f, env, cube);
      });
      hits.store_misses(p, missed, env, cube);
    }
  });
  return hits;
}

}  // namespace ssgi::detail
