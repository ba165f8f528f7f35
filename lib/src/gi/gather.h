// What every tracer hands on: per trace sample, the pixels its hemisphere reaches and the
// fraction of the cosine-weighted hemisphere each brings; the bounce loop gathers over them.
//
// The trace grid is where rays start. At trace scale 1 it is every pixel; at scale s each s x s
// block of the data window traces from one pixel of its own (the one nearest the block's
// median depth, the surface most of the block shows), so that the tracer runs at the
// resolution the denoiser filters at, and the denoiser's pyramid takes the result from there.
// Hits name trace samples, whose light they bring: the tracers run at the trace grid's size
// (its few megabytes stay in cache), not at the frame's.
#pragma once

#include <cstdint>
#include <vector>

#include "march.h"
#include "misses.h"
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

// One row of trace samples' hits as a gather reads them: sample bx's entries are
// [begin[bx], begin[bx + 1]) of `pixel` and of `weight`, or each weighs `uniform_weight` when
// `weight` is null.
struct HitRow {
  const std::uint32_t* begin = nullptr;
  const std::int32_t* pixel = nullptr;
  const float* weight = nullptr;
  float uniform_weight = 0;
};

// Weighted hits of every trace sample.
struct WeightedHits {
  std::vector<std::uint32_t> begin;  // per trace sample, first entry; one more at the end
  std::vector<std::int32_t> pixel;   // trace sample whose light it brings, kSeenFromBehind marked
  std::vector<float> weight;         // its share of the cosine-weighted hemisphere
  Image miss;                        // 1 channel: the share that met nothing
  Image env;                         // 3 channels: environment light of those directions
  Image cube;                        // kCubeFaces channels: their shares of the miss model's cube
  std::size_t entries() const { return pixel.size(); }
  // Row `by`'s hits, of a grid `width` samples across.
  HitRow row(int by, int width) const {
    return {begin.data() + static_cast<std::size_t>(by) * width, pixel.data(), weight.data()};
  }
};

// The march's or the reference's rays as weighted hits (scale 1): each ray 1/rays.
WeightedHits weighted_from_rays(const TraceGrid& grid, const RayHits& rays);

// Storage a HitSource may fill with a row's hits and point its HitRow into.
struct HitScratch {
  std::vector<std::uint32_t> begin;
  std::vector<std::int32_t> pixel;
};

// Where the bounce loop finds each row's hits: held in memory (WeightedHits), or traced again
// for each bounce (the reference beyond its memory budget, reference.h).
class HitSource {
 public:
  virtual ~HitSource() = default;
  // Row `by`'s hits, valid while `scratch` is. Called once per row and bounce, rows in parallel.
  virtual HitRow row(int by, HitScratch* scratch) const = 0;
  // Per trace sample, the share that met nothing (1 channel), the environment light of those
  // directions (3 channels) and their shares of the miss model's cube (kCubeFaces channels); a
  // row's are there once row() has returned it.
  virtual const Image& miss() const = 0;
  virtual const Image& env() const = 0;
  virtual const Image& cube() const = 0;
  // Per trace sample, light that continued rays brought from other frames (3 channels,
  // multiframe.h), the same in every bounce, counted as traced; null when there is none.
  virtual const Image* foreign() const { return nullptr; }
};

// Indirect light at the trace grid after `bounces` gathers over `hits`: a hit brings its
// sample's reflected light plus, from the second bounce on, its albedo x the indirect light it
// gathered in the bounce before (a hit from behind only the latter: surface_model.h); the missed
// share brings its environment light plus its cube shares x the cube colours `misses` finds at
// that bounce (misses.h). 0 where the grid has no origin. With `coverage`, also per trace
// sample (1 channel) the share of the last gather's light that its hits brought rather than the
// miss model (the mean of the three channels; where nothing brought light, the share of the
// hemisphere that met a traced surface): 1 where the result is traced, 0 where it is the miss
// model's estimate, -1 where the grid has no origin. With `last_cube`, the cube colours of the
// last gather.
Image gather_bounces(const TraceGrid& grid, const HitSource& hits, int bounces,
                     const MissModel& misses, Image* coverage = nullptr,
                     CubeLight* last_cube = nullptr);
Image gather_bounces(const TraceGrid& grid, const WeightedHits& hits, int bounces,
                     const MissModel& misses, Image* coverage = nullptr,
                     CubeLight* last_cube = nullptr);

// gather_bounces' coverage (trace samples at `scale` pixels each, -1 without a surface) at the
// resolution of `depth` (the frame's): averaged over each sample's 3 x 3 neighbours on its
// surface (the per-sample share is noisy), then interpolated bilinearly between the samples
// around each pixel that are on its own block's surface and near its depth (its block's value
// when none is). Samples are on one surface when their normals agree and their depths are
// within `thickness` x depth (surface_model.h's slab); grid_depth and grid_normal are the trace
// grid's.
Image coverage_to_frame(const Image& grid_coverage, const Image& grid_depth,
                        const Image& grid_normal, int scale, float thickness, const Image& depth);

}  // namespace ssgi::detail
