// What every tracer hands on: per trace sample, the pixels its hemisphere reaches and the
// fraction of the cosine-weighted hemisphere each brings; the bounce loop gathers over them.

#pragma once

#include <cstdint>
#include <vector>

#include "buffers.h"
#include "gi/march.h"
#include "gi/misses.h"
#include "gi/trace_grid.h"
#include "ssgi/gbuffer.h"
#include "ssgi/image.h"

namespace ssgi::detail {

// One row of trace samples' hits as a gather reads them: sample bx's entries are
// [begin[bx], begin[bx + 1]) of `pixel` and of `weight`, or each weighs `uniform_weight` when
// `weight` is null.
struct HitRow {
  const std::uint32_t* begin = nullptr;
  const std::int32_t* pixel = nullptr;
  const float* weight = nullptr;
  float uniform_weight = 0;
};

// Weighted hits of every trace sample. (Resizing the vectors leaves the new entries for the
// tracer to write, in parallel.)
struct WeightedHits {
  // Per trace sample, its first entry; one more at the end.
  UninitializedVector<std::uint32_t> begin;
  // Per entry, the trace sample whose light it brings (kSeenFromBehind marked), and its share of
  // the cosine-weighted hemisphere.
  UninitializedVector<std::int32_t> pixel;
  UninitializedVector<float> weight;
  Image miss;  // 1 channel: the share that met nothing
  Image env;   // 3 channels: environment light of those directions
  Image cube;  // kCubeFaces channels: their shares of the miss model's cube
  // 3 channels or absent: light that missed rays continued in the frame's views brought
  // (continuation.h, continue_missed_rays), counted as traced; their shares are out of the three
  // above.
  Image continued_light;
  std::size_t entries() const { return pixel.size(); }
  // Row `by`'s hits, of a grid `width` samples across.
  HitRow row(int by, int width) const {
    return {begin.data() + static_cast<std::size_t>(by) * width, pixel.data(), weight.data()};
  }
};

// What a frame's hits leave to the miss model, per trace sample, and the light continued rays
// brought it (WeightedHits' fields of the same names): what continuing rays changes.
struct MissShares {
  Image miss, env, cube;
  Image continued_light;  // 3 channels, or empty before any continuation
};
// The shares moved out of `hits`, and into it.
MissShares take_shares(WeightedHits* hits);
void put_shares(MissShares shares, WeightedHits* hits);

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
  // continuation.h), the same in every bounce, counted as traced; null when there is none.
  virtual const Image* continued_light() const { return nullptr; }
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

// The same over `hits`' entries with `shares` in place of its own (a continuation's,
// continuation.h: the light its continued rays brought counted as traced).
Image gather_bounces(const TraceGrid& grid, const WeightedHits& hits, const MissShares& shares,
                     int bounces, const MissModel& misses, Image* coverage = nullptr);

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
