// One frame's stages, each taking its inputs and returning its result, in the order a frame goes
// through them: trace (the trace grid, the miss model, the tracer's hits), continue in the
// frame's views, gather the bounces, denoise on the trace grid (grid_light); with --multiframe,
// once the window's frames are lit, continue in them and gather what they found
// (continue_in_window); after the temporal stage, the light and its coverage carried to the
// frame's resolution (light_at_frame, coverage_at_frame) and the composite. Without a temporal
// stage, indirect_light goes from trace to the frame's resolution in one pass of the pyramid.
// The sequence processor drives them around the temporal stage; ssgi::Pipeline is their public
// face.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gi/continuation.h"
#include "gi/environment.h"
#include "gi/misses.h"
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
  // (continue_missed_rays) so that light bounces among them; each view's `frame` numbers its noise
  // (read_views gives it the shot's). Empty when the plan continues rays in no view (Plan::views).
  LitViews light_views(const std::vector<GBuffer>& views) const;

  // The frame's light traced and denoised on the trace grid, with what the temporal stage needs
  // of it (TracedLight); with `views`, its missed rays continued in them first.
  TracedLight grid_light(const GBuffer& frame, const LitViews* views = nullptr) const;

  // Plan::multiframe: the light of window[center] (frame `frame`) with its missed rays continued
  // in the other frames of `window` (TracedLight of each, ascending frame order, within
  // Plan::multiframe frames of the centre), gathered again and denoised as grid_light's;
  // nothing when none found a surface (gi/continuation.h). -v reports how many were continued
  // and found one.
  std::optional<ContinuedLight> continue_in_window(const GBuffer& frame,
                                                   const std::vector<const TracedLight*>& window,
                                                   int center) const;

  // Plan::guide: frame g's guide on its trace grid `grid` (TracedLight::grid), for the window.
  GuideOnGrid guide_on_grid(const GBuffer& g, const GBuffer& grid, const GuideFrame& guide) const;

  // Plan::guide: `on_grid` (the light of window[center], frame g, on its trace grid after the
  // temporal stage) with the guides of `window` (TracedLight::guide, ascending frame order):
  // those within `radius` frames carried into it (reprojected, without the light's variance
  // clipping) and averaged over the frames found, then guided_light. -v reports what the guide
  // brought.
  Image guided(const GBuffer& g, const std::vector<const TracedLight*>& window, int center,
               int radius, const Image& on_grid, GuideReport* report = nullptr) const;

  // Light on the trace grid (temporally filtered or not) carried to the frame's resolution by
  // the denoiser's bilateral upsampling.
  Image light_at_frame(const GBuffer& frame, const Image& on_grid) const;

  // TracedLight::coverage at the frame's resolution (1 channel): smoothed over neighbouring
  // trace samples on one surface and interpolated between them; `grid` is TracedLight::grid.
  Image coverage_at_frame(const GBuffer& frame, const GBuffer& grid,
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
  // Tracing: frame g's trace grid, its miss model (what it decided goes to -v's log, or with
  // `misses_note` there) and the tracer's hits; with the slice tracer and `missed_runs` > 0, its
  // missed rays too, that many per slice (continuation.h), for views or other frames to continue.
  std::shared_ptr<FrameTrace> trace(const GBuffer& g, int missed_runs,
                                    std::string* misses_note = nullptr) const;

  // The trace's missed rays continued in the frame's views, into its hits; with `keep_missed`,
  // the rays still missed stay in it for the window's other frames to continue (else none).
  void continue_in_views(FrameTrace* t, const LitViews& views, bool keep_missed) const;

  // Gathering: the light on the trace grid after the plan's bounces over the trace's hits, before
  // the denoiser; with `coverage` and `cube`, gather_bounces' coverage and last cube colours;
  // with `shares`, those of a continuation in place of the hits' own (no cube colours then).
  Image gather(const FrameTrace& t, Image* coverage = nullptr, CubeLight* cube = nullptr,
               const MissShares* shares = nullptr) const;

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
