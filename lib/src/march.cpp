#include "march.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "directions.h"
#include "parallel.h"
#include "surface_model.h"

namespace ssgi::detail {
namespace {

// Rays that head towards the camera are clipped where they reach this fraction of their
// origin's depth: nothing nearer can be in the depth buffer's view.
constexpr float kNearFraction = 1e-3f;
// "Unlimited" rays end this many origin depths away; far enough that their projection is
// within a fraction of a pixel of the vanishing point.
constexpr float kFarFactor = 1e6f;

struct Tracer {
  const GBuffer& g;
  const GiSettings& settings;
  const Environment& env;
  SurfaceModel model;
  DepthMesh mesh;
  int width, height;
  int offset_x, offset_y;  // data window origin in display-window pixels
  double cam_to_world[3][3];
  bool rotate_to_world;

  Tracer(const GBuffer& gb, const GiSettings& s, const Environment& e)
      : g(gb),
        settings(s),
        env(e),
        model{static_cast<float>(s.thickness)},
        mesh(gb.depth, model),
        width(gb.width()),
        height(gb.height()),
        offset_x(gb.data_window.x0 - gb.display_window.x0),
        offset_y(gb.data_window.y0 - gb.display_window.y0),
        rotate_to_world(gb.camera.has_world_transform) {
    const Mat4d inv = rotate_to_world ? gb.camera.world_to_camera.inverse() : Mat4d();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) cam_to_world[i][j] = inv.m[i][j];
  }

  std::array<float, 3> miss_radiance(const Vec3f& d) const {
    if (env.is_constant()) return env.radiance(d);
    const auto& m = cam_to_world;  // row-vector: world = d * M
    const Vec3f w{static_cast<float>(d.x * m[0][0] + d.y * m[1][0] + d.z * m[2][0]),
                  static_cast<float>(d.x * m[0][1] + d.y * m[1][1] + d.z * m[2][1]),
                  static_cast<float>(d.x * m[0][2] + d.y * m[1][2] + d.z * m[2][2])};
    return env.radiance(w);
  }

  // Marches one ray from camera-space origin `o` along unit `d`; returns the index of the
  // pixel whose light it brings, or -1. The ray is projected to the screen and sampled at up to
  // max_steps evenly spaced, jittered points (one per pixel along the major axis when steps
  // allow); its depth is interpolated perspective-correctly (1/z is linear in screen space,
  // McGuire & Mara 2014) and tested against the mesh of surface_model.h.
  int march_ray(const Vec3f& o, const Vec3f& d, float jitter, int self_x, int self_y) const {
    float t_end = settings.max_distance > 0 ? static_cast<float>(settings.max_distance)
                                            : kFarFactor * o.z;
    if (d.z < 0) t_end = std::min(t_end, (o.z - kNearFraction * o.z) / -d.z);
    if (!(t_end > 0)) return -1;
    const Vec3f e{o.x + t_end * d.x, o.y + t_end * d.y, o.z + t_end * d.z};
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
    float f_lo = 0.0f, f_hi = 1.0f;
    auto clip = [&](float p, float q) {
      if (p == 0) return q >= 0;
      const float r = q / p;
      if (p < 0) {
        if (r > f_hi) return false;
        f_lo = std::max(f_lo, r);
      } else {
        if (r < f_lo) return false;
        f_hi = std::min(f_hi, r);
      }
      return true;
    };
    if (!clip(-dx, sx0) || !clip(dx, width - sx0) || !clip(-dy, sy0) ||
        !clip(dy, height - sy0) || !(f_hi > f_lo))
      return -1;
    const bool leaves_screen = f_hi < 1.0f;

    const float span = f_hi - f_lo;
    const float length_px = std::max(std::fabs(dx), std::fabs(dy)) * span;
    const int steps = static_cast<int>(
        std::clamp(std::ceil(length_px), 1.0f, static_cast<float>(settings.max_steps)));
    const float df = span / steps;
    const float inf = std::numeric_limits<float>::infinity();
    // The previous sample, for rays that cross a surface's front between two samples.
    bool prev_valid = false, prev_in_front = false;
    float prev_z = 0.0f;
    for (int i = 0; i < steps; ++i) {
      const float f = f_lo + df * (i + jitter);
      const float sx = sx0 + dx * f, sy = sy0 + dy * f;
      if (static_cast<int>(std::floor(sx)) == self_x && static_cast<int>(std::floor(sy)) == self_y)
        continue;
      MeshPoint surface;
      if (!mesh.surface_at(sx, sy, &surface)) {
        prev_valid = false;
        continue;
      }
      const float hr = h0 + (h1 - h0) * f;
      const float z_ray = hr > 0 ? 1.0f / hr : inf;
      const bool behind_front = z_ray >= surface.z;
      // Inside the slab, or through the front of one continuous surface since the last sample.
      if (behind_front && (z_ray <= model.slab_back(surface.z) ||
                           (prev_valid && prev_in_front && model.connected(prev_z, surface.z))))
        return surface.pixel;
      prev_valid = true;
      prev_in_front = !behind_front;
      prev_z = surface.z;
    }
    if (leaves_screen && settings.miss == MissMode::kExtend)
      return extend_edge(o, d, sx0 + dx * f_hi, sy0 + dy * f_hi);
    return -1;
  }

  // MissMode::kExtend: the surface at the pixel where the ray leaves the screen continues as
  // its tangent plane beyond the edge; a ray that meets that plane from its front side takes
  // the edge pixel's light. Returns the edge pixel's index, or -1.
  int extend_edge(const Vec3f& o, const Vec3f& d, float exit_x, float exit_y) const {
    const int ix = std::clamp(static_cast<int>(std::floor(exit_x)), 0, width - 1);
    const int iy = std::clamp(static_cast<int>(std::floor(exit_y)), 0, height - 1);
    const float ze = g.depth.at(0, ix, iy);
    if (!std::isfinite(ze)) return -1;
    const Vec3f n{g.normal.at(0, ix, iy), g.normal.at(1, ix, iy), g.normal.at(2, ix, iy)};
    const Vec3d pe = g.camera.unproject(ix + offset_x + 0.5, iy + offset_y + 0.5, ze);
    const float facing = n.x * d.x + n.y * d.y + n.z * d.z;
    if (!(facing < 0)) return -1;
    const float t = (n.x * (static_cast<float>(pe.x) - o.x) + n.y * (static_cast<float>(pe.y) - o.y) +
                     n.z * (static_cast<float>(pe.z) - o.z)) /
                    facing;
    if (!(t > 0) || (settings.max_distance > 0 && t > settings.max_distance)) return -1;
    return iy * width + ix;
  }

  // Calls on_ray(k, hit_index, direction) for each ray of surface pixel (x, y).
  template <typename OnRay>
  void trace_pixel(int x, int y, const OnRay& on_ray) const {
    const float z = g.depth.at(0, x, y);
    const int px = x + offset_x, py = y + offset_y;
    const Vec3d p = g.camera.unproject(px + 0.5, py + 0.5, z);
    const Vec3f n{g.normal.at(0, x, y), g.normal.at(1, x, y), g.normal.at(2, x, y)};
    const float off = static_cast<float>(settings.start_offset) * z;
    const Vec3f o{static_cast<float>(p.x) + n.x * off, static_cast<float>(p.y) + n.y * off,
                  static_cast<float>(p.z) + n.z * off};
    const PixelNoise noise = pixel_noise(px, py, g.frame, settings.seed);
    for (int k = 0; k < settings.rays; ++k) {
      float u1, u2, jitter;
      ray_sample(noise, k, &u1, &u2, &jitter);
      const Vec3f d = cosine_hemisphere(n, u1, u2);
      on_ray(k, march_ray(o, d, jitter, x, y), d);
    }
  }
};

}  // namespace

RayHits march_screen_space(const GBuffer& g, const GiSettings& settings, const Environment& env) {
  const Tracer tracer(g, settings, env);
  const int w = g.width(), h = g.height(), rays = settings.rays;
  RayHits hits;
  hits.rays = rays;
  hits.hit.assign(static_cast<std::size_t>(w) * h * rays, -1);
  hits.env_sum = Image(w, h, 3);
  hits.miss_count = Image(w, h, 1);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      std::int32_t* out = &hits.hit[(static_cast<std::size_t>(y) * w + x) * rays];
      float env_sum[3] = {0, 0, 0};
      int misses = 0;
      tracer.trace_pixel(x, y, [&](int k, int hit, const Vec3f& d) {
        out[k] = hit;
        if (hit >= 0) return;
        ++misses;
        if (!env.is_black()) {
          const auto l = tracer.miss_radiance(d);
          for (int c = 0; c < 3; ++c) env_sum[c] += l[c];
        }
      });
      for (int c = 0; c < 3; ++c) hits.env_sum.at(c, x, y) = env_sum[c];
      hits.miss_count.at(0, x, y) = static_cast<float>(misses);
    }
  });
  return hits;
}

Image gather_indirect(const GBuffer& g, const RayHits& hits, const Image& radiance,
                      const MissLight& miss) {
  const int w = g.width(), h = g.height(), rays = hits.rays;
  Image out(w, h, 3);
  const float inv_rays = 1.0f / static_cast<float>(rays);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      const std::size_t pixel = static_cast<std::size_t>(y) * w + x;
      const std::int32_t* hit = &hits.hit[pixel * rays];
      for (int c = 0; c < 3; ++c) {
        const float* l = radiance.plane(c);
        float sum = miss.env_weight * hits.env_sum.plane(c)[pixel] +
                    hits.miss_count.plane(0)[pixel] * miss.frame_radiance[c];
        for (int k = 0; k < rays; ++k)
          if (hit[k] >= 0) sum += l[hit[k]];
        out.plane(c)[pixel] = sum * inv_rays;
      }
    }
  });
  return out;
}

Image march_and_gather(const GBuffer& g, const GiSettings& settings, const Environment& env,
                       const Image& radiance, const MissLight& miss) {
  const Tracer tracer(g, settings, env);
  const int w = g.width(), h = g.height();
  Image out(w, h, 3);
  const float inv_rays = 1.0f / static_cast<float>(settings.rays);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      float sum[3] = {0, 0, 0};
      tracer.trace_pixel(x, y, [&](int, int hit, const Vec3f& d) {
        if (hit >= 0) {
          for (int c = 0; c < 3; ++c) sum[c] += radiance.plane(c)[hit];
        } else {
          std::array<float, 3> l = miss.frame_radiance;
          if (!env.is_black()) {
            const auto e = tracer.miss_radiance(d);
            for (int c = 0; c < 3; ++c) l[c] += miss.env_weight * e[c];
          }
          for (int c = 0; c < 3; ++c) sum[c] += l[c];
        }
      });
      for (int c = 0; c < 3; ++c) out.at(c, x, y) = sum[c] * inv_rays;
    }
  });
  return out;
}

}  // namespace ssgi::detail
