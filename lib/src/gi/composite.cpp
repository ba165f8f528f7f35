#include "gi/composite.h"

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
    const std::size_t row = static_cast<std::size_t>(y) * w;
    const float* depth = g.depth.plane(0) + row;
    for (int c = 0; c < 3; ++c) {
      const float* direct = g.direct.plane(c) + row;
      const float* emitted = emission ? g.emission.plane(c) + row : nullptr;
      float* o = out.plane(c) + row;
      for (int x = 0; x < w; ++x) {
        // Negative light (a renderer's denoiser can leave some) is not a source.
        float v = std::max(0.0f, direct[x]);
        if (emitted) v += std::max(0.0f, emitted[x]);
        o[x] = std::isfinite(depth[x]) ? v : 0.0f;
      }
    }
  });
  return out;
}

FrameResult composite_frame(const GBuffer& g, Image indirect, Image coverage) {
  const int w = g.width(), h = g.height();
  FrameResult r;
  r.indirect = std::move(indirect);
  r.coverage = std::move(coverage);
  const bool with_coverage = !r.coverage.empty();
  r.gi = Image(w, h, 3);
  r.composite = Image(w, h, 4);
  const bool emission = !g.emission.empty(), beauty = !g.beauty.empty();
  parallel_for_rows(h, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    const float* depth = g.depth.plane(0) + row;
    // A surface without diffuse albedo (an emitter, a mirror) reflects no diffuse light: its
    // indirect is 0, as in the renderers' own diffuse passes.
    const float *red = g.albedo.plane(0) + row, *green = g.albedo.plane(1) + row,
                *blue = g.albedo.plane(2) + row;
    for (int c = 0; c < 3; ++c) {
      float* ind = r.indirect.plane(c) + row;
      float* gi = r.gi.plane(c) + row;
      float* out = r.composite.plane(c) + row;
      const float* albedo = g.albedo.plane(c) + row;
      const float* direct = g.direct.plane(c) + row;
      const float* emitted = emission ? g.emission.plane(c) + row : nullptr;
      const float* background = beauty ? g.beauty.plane(c) + row : nullptr;
      for (int x = 0; x < w; ++x) {
        if (!std::isfinite(depth[x])) {
          ind[x] = gi[x] = 0.0f;
          out[x] = background ? finite(background[x]) : 0.0f;
          continue;
        }
        if (red[x] == 0 && green[x] == 0 && blue[x] == 0) ind[x] = 0.0f;
        gi[x] = finite(albedo[x] * ind[x]);
        float rgb = direct[x] + gi[x];
        if (emitted) rgb += emitted[x];
        out[x] = finite(rgb);
      }
    }
    if (with_coverage) {
      float* cov = r.coverage.plane(0) + row;
      for (int x = 0; x < w; ++x)
        cov[x] = std::isfinite(depth[x]) ? std::clamp(finite(cov[x]), 0.0f, 1.0f) : 0.0f;
    }
    float* alpha = r.composite.plane(3) + row;
    const float* beauty_alpha = beauty ? g.beauty.plane(3) + row : nullptr;
    for (int x = 0; x < w; ++x) alpha[x] = beauty_alpha ? finite(beauty_alpha[x]) : 1.0f;
  });
  return r;
}

}  // namespace ssgi::detail
