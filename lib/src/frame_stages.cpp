// One frame's stages: trace, continue in views, gather, denoise on the trace grid; continue in
// the window's frames; carry the light to the frame's resolution; composite.
#include "frame_stages.h"

#include <algorithm>
#include <cmath>

#include "gi/composite.h"
#include "gi/continuation.h"
#include "gi/denoise.h"
#include "gi/gather.h"
#include "gi/guide.h"
#include "gi/march.h"
#include "gi/slices.h"
#include "log.h"
#include "parallel.h"
#include "reference/reference.h"
#include "ssgi/error.h"

namespace ssgi::detail {

FrameStages::FrameStages(const SequenceInfo& seq, const GiSettings& settings,
                         const PipelineMemory& memory)
    : settings_(settings), plan_(make_plan(seq, settings)), memory_(memory) {
  color_ = color_management_for(settings.color, seq);
  for (const std::string& reason : color_.reasons()) plan_.reasons.push_back(reason);
  env_ = settings.env_map.empty()
             ? Environment(settings.env_color)
             : Environment::from_file(settings.env_map, settings.env_up, color_);
}

namespace {

// The trace grid as a G-buffer in grid units, for the temporal stage: its mesh's depth and
// normals, the motion of its traced pixels (in grid pixels), the camera scaled to the grid.
GBuffer grid_gbuffer(const GBuffer& g, const TraceGrid& grid) {
  GBuffer out;
  out.path = g.path;
  out.frame = g.frame;
  out.display_window = out.data_window = {0, 0, grid.width, grid.height};
  out.camera = g.camera;
  out.camera.fx = grid.fx;
  out.camera.fy = grid.fy;
  out.camera.cx = grid.cx;
  out.camera.cy = grid.cy;
  out.depth = grid.depth;
  out.normal = grid.normal;
  const float inv_scale = 1.0f / static_cast<float>(grid.scale);
  auto motion = [&](const Image& full) {
    if (full.channels() < 2) return Image();
    Image m(grid.width, grid.height, 2);
    parallel_for_rows(grid.height, [&](int by) {
      for (int bx = 0; bx < grid.width; ++bx) {
        const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
        const std::int32_t p = grid.origin[s];
        if (p < 0) continue;
        for (int c = 0; c < 2; ++c) m.plane(c)[s] = full.plane(c)[p] * inv_scale;
      }
    });
    return m;
  };
  out.motion_prev = motion(g.motion_prev);
  out.motion_next = motion(g.motion_next);
  return out;
}

// The miss model's cube faces in three groups: the sides (right, left, forward, back), up and
// down (TracedLight::miss_colours).
constexpr int kFaceGroup[kCubeFaces] = {0, 0, 1, 2, 0, 0};

// A tracer's cube shares (6 planes) summed by group, one plane each, so that one pass of the
// denoiser carries them.
Image grouped_shares(const Image& shares) {
  Image grouped(shares.width(), shares.height(), 3);
  const int w = shares.width();
  parallel_for_rows(shares.height(), [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    for (int f = 0; f < kCubeFaces; ++f) {
      const float* in = shares.plane(f) + row;
      float* to = grouped.plane(kFaceGroup[f]) + row;
      for (int x = 0; x < w; ++x) to[x] += in[x];
    }
  });
  return grouped;
}

// The denoiser's pyramid level of a trace scale (1 -> 0, 2 -> 1, 4 -> 2, 8 -> 3).
int pyramid_level(int scale) {
  int level = 0;
  for (int k = scale; k > 1; k /= 2) ++level;
  return level;
}

// With views, a trace sample's shares of the miss model can fall below zero (continuation.h,
// kViewRunsPerSlice), and so can the light of a sample that has little: the denoised light,
// which averages them, is held at zero.
Image held_at_zero(Image light) {
  for (int c = 0; c < light.channels(); ++c) {
    float* p = light.plane(c);
    parallel_for_rows(light.height(), [&](int y) {
      float* row = p + static_cast<std::size_t>(y) * light.width();
      for (int x = 0; x < light.width(); ++x) row[x] = std::max(row[x], 0.0f);
    });
  }
  return light;
}

}  // namespace

std::shared_ptr<FrameTrace> FrameStages::trace(const GBuffer& g, int missed_runs,
                                               std::string* misses_note) const {
  const GiSettings& s = settings_;
  TraceGrid grid =
      make_trace_grid(g, plan_.gather_emission, plan_.trace_scale, static_cast<float>(s.thickness));
  MissModel misses(g, s.miss, env_);
  if (misses_note)
    *misses_note = misses.describe();
  else
    log_info("frame " + std::to_string(g.frame) + ": " + misses.describe());
  auto t = std::make_shared<FrameTrace>(g.frame, g.camera, std::move(grid), WeightedHits(),
                                        std::move(misses), MissedRays());
  switch (s.tracer) {
    case Tracer::kReference:
      t->retraced =
          std::make_shared<const ReferenceHits>(g, s, t->misses, memory_.reference_hits_bytes);
      break;
    case Tracer::kScreenSpace:
      // The march's rays are freed before the bounces.
      t->hits = weighted_from_rays(t->grid, march_screen_space(g, s, t->misses));
      break;
    case Tracer::kSlices:
      t->hits = trace_slices(g, t->grid, s, t->misses, missed_runs > 0 ? &t->missed : nullptr,
                             missed_runs);
      break;
  }
  return t;
}

void FrameStages::continue_in_views(FrameTrace* t, const LitViews& views, bool keep_missed) const {
  std::vector<ContinuationSource> sources;
  for (std::size_t i = 0; i < views.traces.size(); ++i)
    sources.push_back({views.traces[i].get(), &views.light[i]});
  const Continuation continued = continue_into(
      t, sources, continuation_policy(ContinuationPolicy::Kind::kViews), settings_, keep_missed);
  log_info(continued.report.describe(t->frame));
}

Image FrameStages::gather(const FrameTrace& t, Image* coverage, CubeLight* cube,
                          const MissShares* shares) const {
  if (shares) return gather_bounces(t.grid, t.hits, *shares, settings_.bounces, t.misses, coverage);
  if (t.retraced)
    return gather_bounces(t.grid, *t.retraced, settings_.bounces, t.misses, coverage, cube);
  return gather_bounces(t.grid, t.hits, settings_.bounces, t.misses, coverage, cube);
}

Image FrameStages::denoise_on_grid(const GBuffer& g, Image light) const {
  if (!plan_.denoise) return light;
  const int level = pyramid_level(plan_.trace_scale);
  return upsample_and_denoise(light, level, g.depth, g.normal, settings_.denoise_settings, true,
                              level);
}

// Passes of bounces among a frame's views (light_views): each brings one more bounce from the
// other views' light.
constexpr int kViewPasses = 3;

LitViews FrameStages::light_views(const std::vector<GBuffer>& views) const {
  LitViews out;
  if (!plan_.views) return out;
  // The views one per task: each is a few tiny grids whose own parallel loops leave a second
  // thread little to do. Their lines for -v in the order given.
  const std::size_t n = views.size();
  out.traces.resize(n);
  out.light.resize(n);
  std::vector<std::string> notes(n);
  parallel_for_rows(static_cast<int>(n), [&](int i) {
    // Its missed rays kept for the other views to continue.
    out.traces[i] = trace(views[i], kViewRunsPerSlice, &notes[i]);
    out.light[i] = denoise_on_grid(views[i], gather(*out.traces[i]));
  });
  for (std::size_t i = 0; i < n; ++i)
    log_info("frame " + std::to_string(views[i].frame) + ": view " + std::to_string(i + 1) + ": " +
             notes[i]);
  // Light bounces among the views: each one's missed rays continued in the others, which bring
  // their light of the pass before, one more bounce among them each pass (the hits found once).
  if (n < 2) return out;
  std::vector<SourceHits> found(n);
  std::vector<char> continued(n, 0);
  const int passes = std::min(kViewPasses, std::max(1, settings_.bounces - 1));
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<Image> again(n);
    parallel_for_rows(static_cast<int>(n), [&](int i) {
      std::vector<ContinuationSource> others;
      for (std::size_t j = 0; j < n; ++j)
        if (j != static_cast<std::size_t>(i))
          others.push_back({out.traces[j].get(), &out.light[j]});
      FrameTrace& t = *out.traces[i];
      if (pass == 0) {
        Continuation c =
            continue_into(&t, others, continuation_policy(ContinuationPolicy::Kind::kViews),
                          settings_, false, true);
        found[i] = std::move(c.found);
        continued[i] = c.changed();
      } else if (continued[i]) {
        t.hits.continued_light = source_light(t, found[i], others, settings_);
      }
      again[i] = continued[i] ? held_at_zero(denoise_on_grid(views[i], gather(t))) : out.light[i];
    });
    out.light = std::move(again);
  }
  return out;
}

TracedLight FrameStages::grid_light(const GBuffer& g, const LitViews* views) const {
  TracedLight out;
  // The window levels the misses' colours over its frames (window_lights).
  const bool window = plan_.temporal == TemporalMode::kWindow;
  const bool keep = plan_.multiframe > 0;
  const bool with_views = views && !views->empty();
  // The missed rays the window's other frames continue, or the views alone.
  std::shared_ptr<FrameTrace> t = trace(g, keep         ? kMultiframeRunsPerSlice
                                           : with_views ? kViewRunsPerSlice
                                                        : 0);
  if (with_views) continue_in_views(t.get(), *views, keep);
  out.grid = grid_gbuffer(g, t->grid);
  if (window) out.reflected = t->grid.reflected;
  CubeLight cube{};
  out.light = gather(*t, &out.coverage, window ? &cube : nullptr);
  Image shares;
  if (window)
    shares = t->retraced ? t->retraced->cube() : keep ? t->hits.cube : std::move(t->hits.cube);
  // Kept for the window's continuations (this frame's own, and the others' in it); else its hits
  // go before the denoiser's pyramid.
  if (keep) out.trace = std::move(t);
  t.reset();
  out.light = denoise_on_grid(g, std::move(out.light));
  if (shares.channels() != kCubeFaces) return out;
  // Each face's sum in pixel order, the faces in parallel.
  double face_total[kCubeFaces] = {};
  parallel_for_rows(kCubeFaces, [&](int f) {
    const float* in = shares.plane(f);
    double total = 0;
    for (std::size_t p = 0; p < shares.plane_size(); ++p) total += in[p];
    face_total[f] = total;
  });
  for (int group = 0; group < 3; ++group) {
    double weight = 0, colour[3] = {};
    for (int f = 0; f < kCubeFaces; ++f) {
      if (kFaceGroup[f] != group) continue;
      weight += face_total[f];
      for (int c = 0; c < 3; ++c) colour[c] += face_total[f] * cube[f][c];
    }
    for (int c = 0; c < 3; ++c)
      out.miss_colours[group][c] = weight > 0 ? static_cast<float>(colour[c] / weight) : 0.0f;
    out.miss_weight[group] = static_cast<float>(weight);
  }
  // Denoised as the light is (the denoiser's weights do not depend on what it filters), so
  // that a change of colours moves the denoised light as it would have moved the traced one.
  out.miss_shares = denoise_on_grid(g, grouped_shares(shares));
  return out;
}

Image FrameStages::coverage_at_frame(const GBuffer& g, const GBuffer& grid,
                                     const Image& grid_coverage) const {
  return coverage_to_frame(grid_coverage, grid.depth, grid.normal, plan_.trace_scale,
                           static_cast<float>(settings_.thickness), g.depth);
}

GuideOnGrid FrameStages::guide_on_grid(const GBuffer& g, const GBuffer& grid,
                                       const GuideFrame& guide) const {
  return detail::guide_on_grid(g, grid, plan_.trace_scale, guide,
                               static_cast<float>(settings_.thickness));
}

Image FrameStages::guided(const GBuffer& g, const std::vector<const TracedLight*>& window,
                          int center, int radius, const Image& on_grid,
                          GuideReport* out_report) const {
  const TracedLight& own = *window[center];
  // The window's guides carried into this frame and averaged where found, each frame alike: a
  // few-sample render is mostly rare bright samples, which the light's variance clipping would
  // take for change and cut, darkening it; the disocclusion tests alone decide.
  GuideOnGrid guide;
  guide.mean = own.guide.mean;
  guide.known = own.guide.known;
  guide.variance = own.guide.variance;
  Image frames(own.guide.mean.width(), own.guide.mean.height(), 1, 1.0f);
  std::vector<const GBuffer*> grids;
  for (const TracedLight* t : window) grids.push_back(&t->grid);
  const int n = own.grid.frame;
  for (int i = 0; i < static_cast<int>(window.size()); ++i) {
    if (i == center || std::abs(window[i]->grid.frame - n) > radius) continue;
    const GuideOnGrid& other = window[i]->guide;
    Image valid;
    const std::vector<Image> carried =
        reproject(grids, center, i, {&other.mean, &other.known, &other.variance}, &valid);
    const Image &mean = carried[0], &known = carried[1], &variance = carried[2];
    for (std::size_t p = 0; p < frames.plane_size(); ++p) {
      const float v = valid.plane(0)[p];
      frames.plane(0)[p] += v;
      for (int c = 0; c < 3; ++c) {
        guide.mean.plane(c)[p] += v * mean.plane(c)[p];
        guide.known.plane(c)[p] += v * known.plane(c)[p];
        guide.variance.plane(c)[p] += v * variance.plane(c)[p];
      }
    }
  }
  // The means of the frames found, each where its guide is known; the variance of a mean of k
  // frames' means is their mean variance over k. Each frame's variance is seen over a few pixels
  // only, and a few-sample render's noise is mostly rare bright samples that most of those miss:
  // the window's frames together see more of them (this frame's alone over k lit lamplit's
  // detail with noise: tests/accuracy/README.md, "Guides").
  for (std::size_t p = 0; p < frames.plane_size(); ++p) {
    const float k = frames.plane(0)[p];
    for (int c = 0; c < 3; ++c) {
      const float known = guide.known.plane(c)[p];
      guide.mean.plane(c)[p] = known > 0 ? guide.mean.plane(c)[p] / known : 0.0f;
      guide.variance.plane(c)[p] = known > 0 ? guide.variance.plane(c)[p] / (known * known) : 0.0f;
      guide.known.plane(c)[p] = known / k;
    }
  }
  GuideReport report;
  Image out = guided_light(on_grid, guide, own.grid.depth, own.grid.normal,
                           pyramid_level(plan_.trace_scale), settings_.denoise_settings, &report);
  const auto percent = [](double v) { return std::to_string(std::lround(100 * v)) + "%"; };
  log_info("frame " + std::to_string(g.frame) + ": guide: gives the light of " +
           percent(report.known_share) + " of the trace samples; its residual brought " +
           (report.residual_share >= 0 ? "+" : "") + percent(report.residual_share) +
           " of the light, " + percent(report.detail_kept) + " of its detail kept as it is");
  if (out_report) *out_report = report;
  return out;
}

Image FrameStages::light_at_frame(const GBuffer& g, const Image& on_grid) const {
  const int level = pyramid_level(plan_.trace_scale);
  Image light = level == 0 ? on_grid
                           : upsample_and_denoise(on_grid, level, g.depth, g.normal,
                                                  settings_.denoise_settings, false);
  if (plan_.views) return held_at_zero(std::move(light));
  return light;
}

Image FrameStages::indirect_light(const GBuffer& g, Image* coverage, const LitViews* views) const {
  // Without a temporal stage in between, one pass of the pyramid filters and upsamples (its
  // guides are built once): light_at_frame(grid_light(g)) but for the 1e-3 own-value fallback
  // of pixels no coarse sample resembles, which takes the traced light here, the filtered one
  // there.
  const Plan& plan = plan_;
  const int level = pyramid_level(plan.trace_scale);
  const bool with_views = views && !views->empty();
  std::shared_ptr<FrameTrace> t = trace(g, with_views ? kViewRunsPerSlice : 0);
  if (with_views) continue_in_views(t.get(), *views, false);
  Image light = gather(*t, coverage);
  if (coverage)
    *coverage = coverage_to_frame(*coverage, t->grid.depth, t->grid.normal, plan.trace_scale,
                                  static_cast<float>(settings_.thickness), g.depth);
  t.reset();  // the hits before the denoiser's pyramid
  if (level != 0 || plan.denoise)
    light = upsample_and_denoise(light, level, g.depth, g.normal, settings_.denoise_settings,
                                 plan.denoise);
  if (with_views) return held_at_zero(std::move(light));
  return light;
}

std::optional<ContinuedLight> FrameStages::continue_in_window(
    const GBuffer& g, const std::vector<const TracedLight*>& window, int center) const {
  std::vector<const FrameTrace*> frames;
  std::vector<const Image*> lights;
  int c = -1;
  for (int i = 0; i < static_cast<int>(window.size()); ++i) {
    if (!window[i]->trace) continue;
    if (i == center) c = static_cast<int>(frames.size());
    frames.push_back(window[i]->trace.get());
    lights.push_back(&window[i]->light);
  }
  if (c < 0) return std::nullopt;
  const FrameTrace& self = *frames[c];
  const Continuation continued = continue_missed_rays(
      self, {self.hits.miss, self.hits.env, self.hits.cube, self.hits.continued_light},
      window_sources(frames, lights, c), continuation_policy(ContinuationPolicy::Kind::kFrames),
      settings_);
  log_info(continued.report.describe(self.frame));
  if (!continued.changed()) return std::nullopt;  // nothing changes: no need to gather again
  ContinuedLight out;
  out.light = denoise_on_grid(g, gather(self, &out.coverage, nullptr, &continued.shares));
  if (continued.shares.cube.channels() == kCubeFaces)
    out.miss_shares = denoise_on_grid(g, grouped_shares(continued.shares.cube));
  return out;
}

std::string FrameStages::describe_misses(const GBuffer& g) const {
  return MissModel(g, settings_.miss, env_).describe();
}

FrameResult FrameStages::composite(const GBuffer& g, Image indirect, Image coverage) const {
  return composite_frame(g, std::move(indirect), std::move(coverage));
}

FrameResult FrameStages::composite_in_place(GBuffer* g, Image indirect, Image coverage) const {
  return composite_frame_in_place(g, std::move(indirect), std::move(coverage));
}

}  // namespace ssgi::detail
