// The trace grid: the pixels rays start from, and what rays meet there. At trace scale 1 it is
// every pixel; at scale s each s x s block of the data window traces from one pixel of its own (the
// one nearest the block's median depth, the surface most of the block shows), so that the tracer
// runs at the resolution the denoiser filters at, and the denoiser's pyramid takes the result from
// there. Hits name trace samples, whose light they bring: the tracers run at the trace grid's size
// (its few megabytes stay in cache), not at the frame's.
#pragma once

#include <cstdint>
#include <vector>

#include "ssgi/gbuffer.h"
#include "ssgi/image.h"

namespace ssgi::detail {

struct TraceGrid {
  int scale = 1;              // 1, 2 or 4: data-window pixels per trace sample, each axis
  int width = 0, height = 0;  // trace samples across and down
  // Per trace sample: the full-resolution pixel index it traces from, or -1 (no surface).
  std::vector<std::int32_t> origin;
  // What rays meet, per trace sample: the surface at the block's centre (the plane of its
  // origin pixel there; +inf where there is none), that pixel's normal, and the mean
  // reflected light and albedo (clamped to [0, 1]) of the block's pixels on its surface. At
  // scale 1 these are the frame's own values, so the mesh is the frame's (surface_model.h).
  Image depth, normal, reflected, albedo;
  // Per trace sample, its slab's thickness (surface_model.h: feature_thickness).
  Image thickness;
  // The camera in trace-sample units: the data window's pixel coordinates divided by scale.
  float fx = 1, fy = 1, cx = 0, cy = 0;
};

// The grid of trace origins for `g` at `scale`, with what rays meet there; `reflected` is the
// light the frame's surfaces reflect (composite.h); a block's pixels within `thickness` x depth
// of its origin's are on its surface.
TraceGrid make_trace_grid(const GBuffer& g, const Image& reflected, int scale, float thickness);

}  // namespace ssgi::detail
