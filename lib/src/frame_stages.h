// One frame's stages, as the sequence processor drives them around the temporal stage: tracing
// with its misses and bounces, denoising on the trace grid, rays continued in other frames, the
// light carried to the frame's resolution, the composite. ssgi::Pipeline is their public face.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gi/environment.h"
#include "gi/misses.h"
#include "gi/multiframe.h"
#include "gi/temporal.h"
#include "io/color.h"
#include "io/frame_reader.h"
#include "plan.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// A frame's views (--view), lit by FrameStages::light_views: per view, its trace (what the
// frame's rays continued there meet) and its indirect light on its trace grid.
struct LitViews {
  std::vector<std::shared_ptr<FrameTrace>> traces;
  std::vector<Image> light;
  bool empty() const { return traces.empty(); }
};

class FrameStages {
 public:
  // Loads what the whole run shares (the colour config and its processors, the environment
  // map); `memory` bounds what the reference keeps. Throws ssgi::Error.
  FrameStages(const SequenceInfo& sequence, const GiSettings& settings,
              const PipelineMemory& memory = {});

  const Plan& plan() const { return plan_; }
  const GiSettings& settings() const { return settings_; }
  // The run's colour spaces: read_gbuffer takes it, and the outputs go through it.
  const ColorManagement& color() const { return color_; }

  // The frame's views (each as read_views gives it: a pinhole G-buffer with a world transform)
  // lit as frames are, each at its own resolution, with their rays continued in one another
  // (continue_in_views) so that light bounces among them; each view's `frame` numbers its noise
  // (read_views gives it the shot's). Empty when the plan continues rays in no view (Plan::views).
  LitViews light_views(const std::vector<GBuffer>& views) const;

  // The frame's light traced and denoised on the trace grid, with what the temporal stage needs
  // of it (TracedLight); with `views`, its missed rays continued in them first.
  TracedLight trace_light(const GBuffer& frame, const LitViews* views = nullptr) const;

  // Plan::multiframe: TracedLight::light and ::coverage of window[center] (frame `frame`) with
  // its missed rays continued in the other frames of `window` (TracedLight of each, ascending
  // frame order, within Plan::multiframe frames of the centre). False, and nothing written,
  // when none could be (gi/multiframe.h); -v reports how many were and found a surface. With
  // `miss_shares`, the shares of the misses left (as TracedLight::miss_shares: grouped,
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

  // Pipeline::indirect_light, Pipeline::describe_misses and Pipeline::composite.
  Image indirect_light(const GBuffer& frame, Image* coverage = nullptr,
                       const LitViews* views = nullptr) const;
  std::string describe_misses(const GBuffer& frame) const;
  FrameResult composite(const GBuffer& frame, Image indirect, Image coverage = {}) const;
  // composite() written over the frame's albedo and beauty (composite_frame_in_place), for a
  // frame whose passes are not read after it.
  FrameResult composite_in_place(GBuffer* frame, Image indirect, Image coverage = {}) const;

 private:
  // Tracing, misses and bounces on the trace grid: the light before the denoiser, and, when
  // `grid_out` is given, the grid as a G-buffer for the temporal stage, when `coverage` is, the
  // coverage there (gather_bounces), when `keep` is (multiframe), what continuing rays needs.
  // With `cube` and `shares`, the last bounce's cube colours and the samples' shares of them,
  // with `reflected` the light the samples reflect.
  // With `views` (not empty), the missed rays are continued in them before the bounces.
  // What the miss model decided (-v) goes to the log, or with `misses_note` there. The missed
  // rays kept are `kept_runs` per slice (multiframe.h: kViewRunsPerSlice for a view's, which only
  // the other views continue); those the views alone continue, kViewRunsPerSlice.
  Image trace(const GBuffer& g, GBuffer* grid_out, Image* coverage,
              std::shared_ptr<FrameTrace>* keep = nullptr, CubeLight* cube = nullptr,
              Image* shares = nullptr, Image* reflected = nullptr, const LitViews* views = nullptr,
              std::string* misses_note = nullptr, int kept_runs = kMultiframeRunsPerSlice) const;

  // Traced light on the trace grid denoised there (the pyramid from the grid's level), when
  // the plan denoises: TracedLight::light.
  Image denoise_on_grid(const GBuffer& g, Image light) const;

  GiSettings settings_;
  Plan plan_;
  ColorManagement color_;
  Environment env_;
  PipelineMemory memory_;
};

}  // namespace ssgi::detail
