#include "misses.h"

#include <algorithm>

namespace ssgi::detail {

double enclosure(const GBuffer& g) {
  const int w = g.width(), h = g.height();
  const int ring = std::max(1, std::min(w, h) / 50);
  std::size_t border = 0, inward = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int dl = x, dr = w - 1 - x, dt = y, db = h - 1 - y;
      const int nearest = std::min(std::min(dl, dr), std::min(dt, db));
      if (nearest >= ring) continue;
      ++border;
      if (!g.is_surface(x, y)) continue;
      const float nx = g.normal.at(0, x, y), ny = g.normal.at(1, x, y);
      const bool faces_in = (nearest == dt && ny < -0.5f) || (nearest == db && ny > 0.5f) ||
                            (nearest == dl && nx > 0.5f) || (nearest == dr && nx < -0.5f);
      inward += faces_in ? 1 : 0;
    }
  }
  return border ? static_cast<double>(inward) / border : 0.0;
}

double closure_weight(const GBuffer& g, MissMode mode) {
  if (mode == MissMode::kEnvironment || mode == MissMode::kExtend) return 0.0;
  const int w = g.width(), h = g.height();
  std::size_t surfaces = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) surfaces += g.is_surface(x, y) ? 1 : 0;
  const double surface_fraction = static_cast<double>(surfaces) / (static_cast<double>(w) * h);
  if (mode == MissMode::kFrame) return surface_fraction;
  const double t = std::clamp((enclosure(g) - 0.4) / 0.2, 0.0, 1.0);
  return surface_fraction * t * t * (3 - 2 * t);
}

MissLight miss_light(const GBuffer& g, const Image& radiance, double closure) {
  MissLight miss;
  miss.env_weight = static_cast<float>(1.0 - closure);
  if (closure <= 0) return miss;
  const int w = g.width(), h = g.height();
  // Sums in double, in a fixed order: the same bits for any thread count.
  double sum[3] = {0, 0, 0};
  std::size_t surfaces = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      ++surfaces;
      for (int c = 0; c < 3; ++c) sum[c] += radiance.at(c, x, y);
    }
  }
  for (int c = 0; c < 3; ++c)
    miss.frame_radiance[c] = surfaces ? static_cast<float>(closure * sum[c] / surfaces) : 0.0f;
  return miss;
}

Image gather_bounces(const GBuffer& g, const RayHits& hits, const Image& reflected, int bounces,
                     double closure) {
  Image indirect = gather_indirect(g, hits, reflected, miss_light(g, reflected, closure));
  for (int b = 1; b < bounces; ++b) {
    Image radiance = reflected;
    for (int c = 0; c < 3; ++c) {
      float* r = radiance.plane(c);
      const float* a = g.albedo.plane(c);
      const float* ind = indirect.plane(c);
      // Albedo above 1 would add energy at every bounce.
      for (std::size_t p = 0; p < radiance.plane_size(); ++p)
        r[p] += std::clamp(a[p], 0.0f, 1.0f) * ind[p];
    }
    indirect = gather_indirect(g, hits, radiance, miss_light(g, radiance, closure));
  }
  return indirect;
}

}  // namespace ssgi::detail
