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

// The composite of `g` with its albedo and beauty `albedo` and `beauty` (g's own, or r->gi and
// r->composite holding them: each pixel's passes are read before its results are written over
// them) into r->gi and r->composite.
void composite_into(const GBuffer& g, const Image& albedo, const Image& beauty, FrameResult* r) {
  const int w = g.width(), h = g.height();
  const bool with_coverage = !r->coverage.empty();
  const bool emission = !g.emission.empty(), with_beauty = !beauty.empty();
  parallel_for_rows(h, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    const float* depth = g.depth.plane(0) + row;
    const float *reflectance[3], *direct[3], *emitted[3] = {}, *background[3] = {};
    float *ind[3], *gi[3], *out[3];
    for (int c = 0; c < 3; ++c) {
      reflectance[c] = albedo.plane(c) + row;
      direct[c] = g.direct.plane(c) + row;
      if (emission) emitted[c] = g.emission.plane(c) + row;
      if (with_beauty) background[c] = beauty.plane(c) + row;
      ind[c] = r->indirect.plane(c) + row;
      gi[c] = r->gi.plane(c) + row;
      out[c] = r->composite.plane(c) + row;
    }
    for (int x = 0; x < w; ++x) {
      if (!std::isfinite(depth[x])) {
        for (int c = 0; c < 3; ++c) {
          const float behind = with_beauty ? finite(background[c][x]) : 0.0f;
          ind[c][x] = gi[c][x] = 0.0f;
          out[c][x] = behind;
        }
        continue;
      }
      // A surface without diffuse albedo (an emitter, a mirror) reflects no diffuse light: its
      // indirect is 0, as in the renderers' own diffuse passes.
      const bool no_albedo =
          reflectance[0][x] == 0 && reflectance[1][x] == 0 && reflectance[2][x] == 0;
      for (int c = 0; c < 3; ++c) {
        if (no_albedo) ind[c][x] = 0.0f;
        const float reflected = finite(reflectance[c][x] * ind[c][x]);
        float rgb = direct[c][x] + reflected;
        if (emission) rgb += emitted[c][x];
        gi[c][x] = reflected;
        out[c][x] = finite(rgb);
      }
    }
    if (with_coverage) {
      float* cov = r->coverage.plane(0) + row;
      for (int x = 0; x < w; ++x)
        cov[x] = std::isfinite(depth[x]) ? std::clamp(finite(cov[x]), 0.0f, 1.0f) : 0.0f;
    }
    float* alpha = r->composite.plane(3) + row;
    const float* beauty_alpha = with_beauty ? beauty.plane(3) + row : nullptr;
    for (int x = 0; x < w; ++x) alpha[x] = beauty_alpha ? finite(beauty_alpha[x]) : 1.0f;
  });
}

}  // namespace

FrameResult composite_frame(const GBuffer& g, Image indirect, Image coverage) {
  FrameResult r;
  r.indirect = std::move(indirect);
  r.coverage = std::move(coverage);
  r.gi = Image(g.width(), g.height(), 3);
  r.composite = Image(g.width(), g.height(), 4);
  composite_into(g, g.albedo, g.beauty, &r);
  return r;
}

FrameResult composite_frame_in_place(GBuffer* g, Image indirect, Image coverage) {
  FrameResult r;
  r.indirect = std::move(indirect);
  r.coverage = std::move(coverage);
  r.gi = std::move(g->albedo);
  const bool over_beauty = g->beauty.channels() == 4;
  r.composite = over_beauty ? std::move(g->beauty) : Image(g->width(), g->height(), 4);
  composite_into(*g, r.gi, over_beauty ? r.composite : g->beauty, &r);
  // A moved-from Image keeps its size: these are made absent.
  g->albedo = Image();
  g->beauty = Image();
  return r;
}

}  // namespace ssgi::detail
