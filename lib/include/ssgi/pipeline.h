// The GI pipeline: the plan of what runs, and the per-frame stages from directions to
// composite.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "ssgi/color.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"
#include "ssgi/settings.h"

namespace ssgi {

namespace detail {
struct FrameTrace;
}

// What a run does, decided once from what the inputs provide and what the user asked: the
// only place that chooses stages, channels and buffers.
struct Plan {
  RoleMask roles = 0;            // the channels the reader reads
  bool gather_emission = false;  // emission is part of the light rays pick up
  int trace_scale = 1;           // data-window pixels per trace sample, each axis
  bool env_map = false;          // misses look up an environment map
  bool denoise = false;
  TemporalMode temporal = TemporalMode::kNone;
  int multiframe = 0;                // frames each side that missed rays are continued in (0: none)
  std::vector<std::string> reasons;  // one line per decision, for `ssgi info` and -v
};

// Decides the plan for `sequence` under `settings`.
Plan make_plan(const SequenceInfo& sequence, const GiSettings& settings);

// One frame's results, each covering the data window.
struct FrameResult {
  Image indirect;   // 3: diffuse indirect light without albedo (Cycles' DiffInd)
  Image gi;         // 3: albedo x indirect
  Image composite;  // 4: direct + emission + gi on surfaces, the input beauty elsewhere
  // 1: the share of the indirect light that traced rays brought (1) rather than the miss
  // model's estimate of what lies off screen or behind everything (0); 0 on background. Empty
  // when the caller gave none to composite().
  Image coverage;
};

// What the pipeline may hold besides its frames' planes. It does not change the light.
struct PipelineMemory {
  // The Embree reference keeps, for the bounces after the first, the hits of as many rows as
  // fit in this many bytes (4 per ray), and traces the other rows again for each bounce.
  std::size_t reference_hits_bytes = std::size_t{1} << 30;
  // Frames between reading and writing at once in run_sequence: 3 reads the next frame and
  // writes the last while lighting one; 2 overlaps two of those; 1 does one after the other.
  // 2 by default: as fast as 3 on a 1080p shot (2 cores), 90 MB less without passthrough and
  // 430 MB less with it (tests/bench/end_to_end.sh; README, Speed and memory).
  int frames_in_flight = 2;
  // The symmetric window finishes a frame only after its later neighbours are lit. Kept (the
  // default), a frame waiting for them holds its full-resolution passes (with passthrough, its
  // input's pixels); read twice, it holds only its light on the trace grid and is decoded again
  // to be finished and written: the least memory, for a second decoding of each frame written
  // (the same bits either way).
  bool read_twice = false;
};

class Pipeline {
 public:
  // Loads what the whole run shares (the colour config and its processors, the environment
  // map); `memory` bounds what the reference keeps. Throws ssgi::Error.
  Pipeline(const SequenceInfo& sequence, const GiSettings& settings,
           const PipelineMemory& memory = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  const Plan& plan() const;
  const GiSettings& settings() const;
  // The run's colour spaces: read_gbuffer takes it, and the outputs go through it.
  const ColorManagement& color() const;

  // RGB per group of the miss model's cube faces: sideways, up, down.
  using MissColours = std::array<std::array<float, 3>, 3>;

  // The light as traced (misses and bounces included) and denoised, at the trace grid's
  // resolution, with the grid's geometry as a G-buffer in grid units (depth, normals, motion and
  // camera; windows from (0, 0)): what the temporal stage filters.
  struct TracedLight {
    GBuffer grid;
    Image light;     // 3 channels, the grid's size
    Image coverage;  // 1 channel, the grid's size: FrameResult::coverage there (-1: no surface)
    // With Plan::multiframe, what continuing its rays and being continued in needs.
    std::shared_ptr<detail::FrameTrace> trace;
    // The temporal window's: the colours the miss model's cube (lib/src/gi/misses.h) gave the
    // last bounce's misses heading sideways, up and down (RGB each; the sides' four faces
    // weighted by their shares over the frame), and each trace sample's shares of those three,
    // denoised as the light is (3 channels; empty when the plan has no window).
    MissColours miss_colours{};
    std::array<float, 3> miss_weight{};  // each group's share of the frame's misses (0: none)
    Image miss_shares;
    Image reflected;  // 3 channels, the grid's size: the light its surfaces reflect
  };
  TracedLight trace_light(const GBuffer& frame) const;

  // The temporal window's lights (TracedLight::light of each of `window`) with the miss model's
  // colours of the last bounce levelled over the window: each frame's light plus its shares x
  // (the levelled colours - its own), a group's levelled colour being the mean of its colours
  // over the window's frames lit alike (those with misses in that group). A frame's border
  // shows other surroundings as the view moves; the window's frames together show more, and
  // agree. Two frames are lit alike when the surfaces both show reflect the same light, to
  // 1.25x (detail::shared_light_ratio): a lamp entering the view changes what a frame shows, a
  // flash changes the light of what both show; frames that share no surface are not. Frames
  // without shares are as they are. With `changes`, each frame's levelled colours minus its own
  // (0 where it was left as it is): what its light moved by per unit of its shares.
  std::vector<Image> window_lights(const std::vector<const TracedLight*>& window,
                                   std::vector<MissColours>* changes = nullptr) const;

  // Plan::multiframe: TracedLight::light and ::coverage of window[center] (frame `frame`) with
  // its missed rays continued in the other frames of `window` (TracedLight of each, ascending
  // frame order, within Plan::multiframe frames of the centre). False, and nothing written,
  // when none could be (lib/src/gi/multiframe.h); -v reports how many were and found a surface.
  // With `miss_shares`, the shares of the misses left (as TracedLight::miss_shares: grouped,
  // denoised as the light is).
  bool continue_light(const GBuffer& frame, const std::vector<const TracedLight*>& window,
                      int center, Image* light, Image* coverage,
                      Image* miss_shares = nullptr) const;

  // Light on the trace grid (temporally filtered or not) carried to the frame's resolution by
  // the denoiser's bilateral upsampling.
  Image finish_light(const GBuffer& frame, const Image& grid_light) const;

  // TracedLight::coverage at the frame's resolution (1 channel): smoothed over neighbouring
  // trace samples on one surface and interpolated between them; `grid` is TracedLight::grid.
  Image finish_coverage(const GBuffer& frame, const GBuffer& grid,
                        const Image& grid_coverage) const;

  // trace_light then finish_light: the frame's indirect light (3 channels) without temporal
  // filtering; with `coverage`, its coverage at the frame's resolution too.
  Image indirect_light(const GBuffer& frame, Image* coverage = nullptr) const;

  // What the miss model decides for `frame` (lib/src/gi/misses.h; man ssgi, MISSES) and the
  // numbers it decides from, in one line: what -v prints per frame.
  std::string describe_misses(const GBuffer& frame) const;

  // The composite stage: outputs from the (temporally filtered) indirect light, and its
  // coverage at the frame's resolution when given (FrameResult::coverage).
  FrameResult composite(const GBuffer& frame, Image indirect, Image coverage = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ssgi
