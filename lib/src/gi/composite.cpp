#include "composite.h"

#include <algorithm>
#include <cmath>

#include "parallel.h"

namespace ssgi::detail {
namespace {

// Keeps outputs finite whatever the inputs: inputs are clamped to +-1e30 by the reader, and
// sums of a few of them stay far below float's range.
float finite(float v) {
  return std::isfinite(v) ? v : (std::isnan(v) ? 0.0f : std::copysign(3e38f, v));
}

}  // namespace

Image reflected_radiance(const GBuffer& g, bool with_emission) {
  const int w = g.width(), h = g.height();
  Image out(w, h, 3);
  const bool emission = with_emission && !g.emission.empty();
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      for (int c = 0; c < 3; ++c) {
        // Negative light (a renderer's denoiser can leave some) is not a source.
        float v = std::max(0.0f, g.direct.at(c, x, y));
        if (emission) v += std::max(0.0f, g.emission.at(c, x, y));
        out.at(c, x, y) = v;
      }
    }
  });
  return out;
}

FrameResult composite_frame(const GBuffer& g, Image indirect) {
  const int w = g.width(), h = g.height();
  FrameResult r;
  r.indirect = std::move(indirect);
  r.gi = Image(w, h, 3);
  r.composite = Image(w, h, 4);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const bool surface = g.is_surface(x, y);
      for (int c = 0; c < 3; ++c) {
        float& ind = r.indirect.at(c, x, y);
        if (!surface) ind = 0.0f;
        const float gi = surface ? finite(g.albedo.at(c, x, y) * ind) : 0.0f;
        r.gi.at(c, x, y) = gi;
        float rgb;
        if (surface) {
          rgb = g.direct.at(c, x, y) + gi;
          if (!g.emission.empty()) rgb += g.emission.at(c, x, y);
        } else {
          rgb = g.beauty.empty() ? 0.0f : g.beauty.at(c, x, y);
        }
        r.composite.at(c, x, y) = finite(rgb);
      }
      r.composite.at(3, x, y) = g.beauty.empty() ? 1.0f : finite(g.beauty.at(3, x, y));
    }
  });
  return r;
}

}  // namespace ssgi::detail
