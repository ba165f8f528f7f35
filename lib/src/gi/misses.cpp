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

}  // namespace ssgi::detail
