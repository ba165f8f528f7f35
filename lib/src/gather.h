// What every tracer hands on: per trace sample, the pixels its hemisphere reaches and the
// fraction of the cosine-weighted hemisphere each brings; the bounce loop gathers over them.
//
// The trace grid is where rays start. At trace scale 1 it is every pixel; at scale s each s x s
// block of the data window traces from one pixel of its own (the one nearest the block's
// median depth, the surface most of the block shows), so that the tracer runs at the
// resolution the denoiser filters at, and the denoiser's pyramid takes the result from there.
// Hits always name full-resolution pixels, whose own light they bring.
#pragma once

#include <cstdint>
#include <vector>

#include "march.h"
#include "ssgi/gbuffer.h"

namespace ssgi::detail {

struct TraceGrid {
  int scale = 1;              // 1, 2 or 4: data-window pixels per trace sample, each axis
  int width = 0, height = 0;  // trace samples across and down
  int full_width = 0;         // the data window's width
  // Per trace sample: the full-resolution pixel index it traces from, or -1 (no surface).
  std::vector<std::int32_t> origin;

  // The trace sample whose block holds full-resolution pixel `pixel`.
  int block_of(int pixel) const {
    const int x = pixel % full_width, y = pixel / full_width;
    return (y / scale) * width + x / scale;
  }
};

// The grid of trace origins for `g` at `scale`.
TraceGrid make_trace_grid(const GBuffer& g, int scale);

// Weighted hits of every trace sample.
struct WeightedHits {
  std::vector<std::uint32_t> begin;  // per trace sample, first entry; one more at the end
  std::vector<std::int32_t> pixel;   // full-resolution pixel whose light the entry brings
  std::vector<float> weight;         // its share of the cosine-weighted hemisphere
  Image miss;                        // 1 channel: the share that met nothing
  Image env;                         // 3 channels: environment light of those directions
  std::size_t entries() const { return pixel.size(); }
};

// The march's or the reference's rays as weighted hits (scale 1): each ray 1/rays.
WeightedHits weighted_from_rays(const TraceGrid& grid, const RayHits& rays);

// Indirect light at the trace grid after `bounces` gathers over `hits`: a hit brings its
// pixel's `reflected` light plus, from the second bounce on, albedo x the indirect light its
// block gathered in the bounce before; the missed share brings the miss model's light
// (misses.h, with `closure` from closure_weight). 0 where the grid has no origin.
Image gather_bounces(const GBuffer& g, const TraceGrid& grid, const WeightedHits& hits,
                     const Image& reflected, int bounces, double closure);

}  // namespace ssgi::detail
