// The plan and the per-frame pipeline: directions -> march -> misses -> bounces -> denoise,
// and the composite after the temporal stage.
#include "ssgi/pipeline.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "composite.h"
#include "denoise.h"
#include "environment.h"
#include "gather.h"
#include "march.h"
#include "misses.h"
#include "multiframe.h"
#include "parallel.h"
#include "reference.h"
#include "slices.h"
#include "ssgi/error.h"
#include "ssgi/log.h"
#include "temporal.h"

namespace ssgi {
namespace {

std::string color_string(const std::array<float, 3>& c) {
  std::ostringstream s;
  s << c[0] << "," << c[1] << "," << c[2];
  return s.str();
}

void validate(const GiSettings& s) {
  if (s.rays < 1 || s.rays > 4096) throw_usage("--rays must be between 1 and 4096");
  if (s.max_steps < 1 || s.max_steps > 1 << 20)
    throw_usage("--max-steps must be between 1 and 1048576");
  if (s.slices < 1 || s.slices > 256) throw_usage("--slices must be between 1 and 256");
  if (s.trace_scale != 0 && s.trace_scale != 1 && s.trace_scale != 2 && s.trace_scale != 4 &&
      s.trace_scale != 8)
    throw_usage("--trace-scale must be auto, 1, 2, 4 or 8");
  if (s.trace_width < 1) throw_usage("the preset's trace width must be at least 1");
  if (s.tracer == Tracer::kSlices && s.miss == MissMode::kExtend)
    throw_usage("--miss extend needs the march (--tracer march)");
  // Beyond 1e30 a distance no longer fits the march's float arithmetic; 0 means unlimited.
  if (!(s.max_distance >= 0) || !(s.max_distance <= 1e30))
    throw_usage("--max-distance must be between 0 (unlimited) and 1e30");
  if (!(s.thickness > 0) || !std::isfinite(s.thickness)) throw_usage("--thickness must be > 0");
  if (!(s.start_offset >= 0) || s.start_offset > 1)
    throw_usage("--start-offset must be between 0 and 1");
  if (s.bounces < 1 || s.bounces > 64) throw_usage("--bounces must be between 1 and 64");
  for (float c : s.env_color)
    if (!(c >= 0) || !std::isfinite(c)) throw_usage("--env-color must be finite and >= 0");
  if (s.env_up != 'y' && s.env_up != 'z') throw_usage("--env-up must be y or z");
  if (s.temporal_radius < 1 || s.temporal_radius > 64)
    throw_usage("--temporal window:K needs K between 1 and 64");
  if (s.multiframe < 0 || s.multiframe > 64)
    throw_usage("--multiframe on:K needs K between 1 and 64");
  if (!(s.ema_alpha > 0 && s.ema_alpha <= 1))
    throw_usage("--temporal ema:ALPHA needs ALPHA in (0, 1]");
  detail::validate_denoise_settings(s.denoise_settings);
}

}  // namespace

Plan make_plan(const SequenceInfo& seq, const GiSettings& s) {
  validate(s);
  const Layout& layout = seq.layout;
  Plan plan;
  auto need = [&](Role role, const std::string& why) {
    plan.roles |= role_bit(role);
    plan.reasons.push_back(std::string("read ") + role_name(role) + ": " + why);
  };
  need(Role::kDepth, "the surfaces rays start from and hit");
  if (seq.context)
    plan.reasons.push_back("context: " + seq.context->pattern.path_for(seq.frames.front()) +
                           " and its sequence fill the picture around the data window (--context)");
  if (seq.normals_from_depth) {
    plan.roles |= role_bit(Role::kNormal);
    plan.reasons.push_back(
        "normal: from the depth buffer's pixel derivatives (--normals depth, or the file has "
        "none), the hemisphere each pixel gathers over");
  } else {
    need(Role::kNormal, "the hemisphere each pixel gathers over");
  }
  if (!layout.has(Role::kDirect))
    throw_input(seq.pattern.path_for(seq.frames.front()),
                "has no direct-light channels (give --channel direct=NAME)");
  need(Role::kDirect, "the light surfaces reflect");
  if (!layout.has(Role::kAlbedo))
    throw_input(seq.pattern.path_for(seq.frames.front()),
                "has no albedo channels (give --channel albedo=NAME)");
  need(Role::kAlbedo, layout.preset.direct_includes_albedo ? "gi = albedo x indirect"
                                                           : "direct light x albedo, and gi");
  plan.gather_emission =
      s.gather_emission < 0 ? layout.preset.gather_emission : s.gather_emission > 0;
  if (layout.has(Role::kEmission)) {
    need(Role::kEmission, plan.gather_emission ? "added to the composite and gathered by rays"
                                               : "added to the composite (not gathered: the "
                                                 "renderer samples emitters as lights)");
  } else {
    plan.gather_emission = false;
  }
  if (layout.has(Role::kBeauty))
    need(Role::kBeauty, "background pixels and alpha of the composite");
  plan.env_map = !s.env_map.empty();
  const std::string env = plan.env_map
                              ? "environment map " + s.env_map + " (up axis " + s.env_up + ")"
                              : "constant colour " + color_string(s.env_color);
  std::string misses = std::string("misses (--miss ") + miss_mode_name(s.miss) + "): ";
  switch (s.miss) {
    case MissMode::kEnvironment:
      misses += env;
      break;
    case MissMode::kFrame:
      misses +=
          "an enclosed world: the light of the frame's surfaces facing the ray (an ambient "
          "cube from the frame's border), no sky";
      break;
    case MissMode::kExtend:
      misses += "the surface at the screen edge extended as its plane, else " + env;
      break;
    case MissMode::kAuto:
      misses += "per frame and direction, the sky's share by elevation (" + env +
                ") and the light of the frame's surfaces facing the ray where the frame's border "
                "shows surfaces facing that way (-v prints each frame's numbers)";
      break;
  }
  plan.reasons.push_back(misses);
  plan.trace_scale = 1;
  if (s.tracer == Tracer::kSlices) {
    plan.trace_scale = s.trace_scale;
    if (plan.trace_scale == 0) {
      plan.trace_scale = 1;
      while (plan.trace_scale < 8 &&
             seq.working_window().width() / (2 * plan.trace_scale) >= s.trace_width)
        plan.trace_scale *= 2;
    }
  }
  const std::string bounces =
      std::to_string(s.bounces) + " bounce" +
      (s.bounces > 1 ? "s (hits kept and re-gathered for each further bounce)" : "");
  switch (s.tracer) {
    case Tracer::kReference:
      plan.reasons.push_back("trace: Embree against the depth mesh, " + std::to_string(s.rays) +
                             " rays per pixel, " + bounces);
      break;
    case Tracer::kScreenSpace:
      plan.reasons.push_back("trace: march, " + std::to_string(s.rays) +
                             " rays per pixel, exact walk up to " + std::to_string(s.max_steps) +
                             " pixels, sampled beyond, " + bounces);
      break;
    case Tracer::kSlices:
      plan.reasons.push_back(
          "trace: slices (visibility bitmask), " + std::to_string(s.slices) + " slices of 32 " +
          "sectors and " + std::to_string(s.max_steps) + " samples a side from " +
          (plan.trace_scale == 1 ? std::string("every pixel")
                                 : "one pixel in " + std::to_string(plan.trace_scale) + "x" +
                                       std::to_string(plan.trace_scale)) +
          ", " + bounces);
      break;
  }
  plan.denoise = s.denoise == DenoiseMode::kPyramid;
  plan.reasons.push_back(plan.denoise ? "denoise: bilateral pyramid" : "denoise: none");
  plan.temporal = s.temporal;
  if (seq.frames_on_disk.size() <= 1) {
    plan.temporal = TemporalMode::kNone;
    plan.reasons.push_back("temporal: none (a single frame)");
  } else if (plan.temporal == TemporalMode::kNone) {
    plan.reasons.push_back("temporal: none (--temporal none)");
  } else {
    if (plan.temporal == TemporalMode::kWindow)
      plan.reasons.push_back("temporal: symmetric window of +-" +
                             std::to_string(s.temporal_radius) +
                             " frames on disk around each output frame (chunk-independent)");
    else
      plan.reasons.push_back("temporal: exponential moving average, alpha " +
                             std::to_string(s.ema_alpha) + ", pre-roll before the first frame");
    if (layout.has(Role::kMotion))
      need(Role::kMotion, "moving objects' history follows their motion vectors");
    else
      plan.reasons.push_back(
          "no motion vectors: history through the cameras, moving objects "
          "rejected by the depth and normal tests");
  }
  if (s.multiframe > 0) {
    if (plan.temporal != TemporalMode::kWindow) {
      plan.reasons.push_back(
          "multiframe: off (it continues rays in the temporal window's frames: "
          "needs --temporal window)");
    } else if (s.tracer != Tracer::kSlices) {
      plan.reasons.push_back("multiframe: off (the slice tracer's misses only)");
    } else {
      plan.multiframe = std::min(s.multiframe, s.temporal_radius);
      plan.reasons.push_back(
          "multiframe: missed rays continued in the depth buffers of up to " +
          std::to_string(plan.multiframe) +
          " frames each side, through their cameras (static geometry; frames whose camera "
          "has no world transform, or is the frame's own, add nothing)");
    }
  }
  plan.reasons.push_back("composite: direct + emission + albedo x indirect");
  return plan;
}

struct Pipeline::Impl {
  GiSettings settings;
  Plan plan;
  ColorManagement color;
  detail::Environment env;
  PipelineMemory memory;

  // Tracing, misses and bounces on the trace grid: the light before the denoiser, and, when
  // `grid_out` is given, the grid as a G-buffer for the temporal stage, when `coverage` is, the
  // coverage there (gather_bounces), when `keep` is (multiframe), what continuing rays needs.
  // With `cube` and `shares`, the last bounce's cube colours and the samples' shares of them,
  // with `reflected` the light the samples reflect.
  Image trace(const GBuffer& g, GBuffer* grid_out, Image* coverage,
              std::shared_ptr<detail::FrameTrace>* keep = nullptr,
              detail::CubeLight* cube = nullptr, Image* shares = nullptr,
              Image* reflected = nullptr) const;

  // Traced light on the trace grid denoised there (the pyramid from the grid's level), when
  // the plan denoises: TracedLight::light.
  Image denoise_on_grid(const GBuffer& g, Image light) const;
};

Pipeline::Pipeline(const SequenceInfo& seq, const GiSettings& settings,
                   const PipelineMemory& memory)
    : impl_(std::make_unique<Impl>()) {
  impl_->settings = settings;
  impl_->memory = memory;
  impl_->plan = make_plan(seq, settings);
  impl_->color = color_management_for(settings.color, seq);
  for (const std::string& reason : impl_->color.reasons()) impl_->plan.reasons.push_back(reason);
  impl_->env = settings.env_map.empty() ? detail::Environment(settings.env_color)
                                        : detail::Environment::from_file(
                                              settings.env_map, settings.env_up, impl_->color);
}

Pipeline::~Pipeline() = default;

const Plan& Pipeline::plan() const { return impl_->plan; }
const GiSettings& Pipeline::settings() const { return impl_->settings; }
const ColorManagement& Pipeline::color() const { return impl_->color; }

namespace {

// The trace grid as a G-buffer in grid units, for the temporal stage: its mesh's depth and
// normals, the motion of its traced pixels (in grid pixels), the camera scaled to the grid.
GBuffer grid_gbuffer(const GBuffer& g, const detail::TraceGrid& grid) {
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
    for (std::size_t s = 0; s < grid.origin.size(); ++s) {
      const std::int32_t p = grid.origin[s];
      if (p < 0) continue;
      for (int c = 0; c < 2; ++c) m.plane(c)[s] = full.plane(c)[p] * inv_scale;
    }
    return m;
  };
  out.motion_prev = motion(g.motion_prev);
  out.motion_next = motion(g.motion_next);
  return out;
}

// The miss model's cube faces in three groups: the sides (right, left, forward, back), up and
// down (TracedLight::miss_colours).
constexpr int kFaceGroup[detail::kCubeFaces] = {0, 0, 1, 2, 0, 0};

// A tracer's cube shares (6 planes) summed by group, one plane each, so that one pass of the
// denoiser carries them.
Image grouped_shares(const Image& shares) {
  Image grouped(shares.width(), shares.height(), 3);
  for (int f = 0; f < detail::kCubeFaces; ++f) {
    const float* in = shares.plane(f);
    float* to = grouped.plane(kFaceGroup[f]);
    for (std::size_t p = 0; p < shares.plane_size(); ++p) to[p] += in[p];
  }
  return grouped;
}

// The denoiser's pyramid level of a trace scale (1 -> 0, 2 -> 1, 4 -> 2, 8 -> 3).
int pyramid_level(int scale) {
  int level = 0;
  for (int k = scale; k > 1; k /= 2) ++level;
  return level;
}

}  // namespace

Image Pipeline::Impl::trace(const GBuffer& g, GBuffer* grid_out, Image* coverage,
                            std::shared_ptr<detail::FrameTrace>* keep, detail::CubeLight* cube,
                            Image* shares, Image* reflected_out) const {
  const GiSettings& s = settings;
  const Image reflected = detail::reflected_radiance(g, plan.gather_emission);
  detail::TraceGrid grid =
      detail::make_trace_grid(g, reflected, plan.trace_scale, static_cast<float>(s.thickness));
  const detail::MissModel misses(g, s.miss, env);
  if (reflected_out) *reflected_out = grid.reflected;
  log_info("frame " + std::to_string(g.frame) + ": " + misses.describe());
  if (grid_out) *grid_out = grid_gbuffer(g, grid);
  switch (s.tracer) {
    case Tracer::kReference: {
      const detail::ReferenceHits hits(g, s, misses, memory.reference_hits_bytes);
      Image light = detail::gather_bounces(grid, hits, s.bounces, misses, coverage, cube);
      if (shares) *shares = hits.cube();
      return light;
    }
    case Tracer::kScreenSpace: {
      // The march's rays are freed before the bounces.
      detail::WeightedHits hits =
          detail::weighted_from_rays(grid, detail::march_screen_space(g, s, misses));
      Image light = detail::gather_bounces(grid, hits, s.bounces, misses, coverage, cube);
      if (shares) *shares = std::move(hits.cube);
      return light;
    }
    case Tracer::kSlices:
      break;
  }
  detail::MissedRays missed;
  detail::WeightedHits hits = detail::trace_slices(g, grid, s, misses, keep ? &missed : nullptr);
  Image light = detail::gather_bounces(grid, hits, s.bounces, misses, coverage, cube);
  if (shares) *shares = hits.cube;
  if (!keep) return light;
  *keep = std::make_shared<detail::FrameTrace>(g.frame, g.camera, std::move(grid), std::move(hits),
                                               misses, std::move(missed));
  return light;
}

Image Pipeline::Impl::denoise_on_grid(const GBuffer& g, Image light) const {
  if (!plan.denoise) return light;
  const int level = pyramid_level(plan.trace_scale);
  return detail::upsample_and_denoise(light, level, g.depth, g.normal, settings.denoise_settings,
                                      true, level);
}

Pipeline::TracedLight Pipeline::trace_light(const GBuffer& g) const {
  TracedLight out;
  // The window levels the misses' colours over its frames (window_lights).
  const bool window = impl_->plan.temporal == TemporalMode::kWindow;
  detail::CubeLight cube{};
  Image shares;
  out.light = impl_->trace(
      g, &out.grid, &out.coverage, impl_->plan.multiframe > 0 ? &out.trace : nullptr,
      window ? &cube : nullptr, window ? &shares : nullptr, window ? &out.reflected : nullptr);
  out.light = impl_->denoise_on_grid(g, std::move(out.light));
  if (shares.channels() != detail::kCubeFaces) return out;
  double face_total[detail::kCubeFaces] = {};
  for (int f = 0; f < detail::kCubeFaces; ++f) {
    const float* in = shares.plane(f);
    for (std::size_t p = 0; p < shares.plane_size(); ++p) face_total[f] += in[p];
  }
  for (int group = 0; group < 3; ++group) {
    double weight = 0, colour[3] = {};
    for (int f = 0; f < detail::kCubeFaces; ++f) {
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
  out.miss_shares = impl_->denoise_on_grid(g, grouped_shares(shares));
  return out;
}

std::vector<Image> Pipeline::window_lights(const std::vector<const TracedLight*>& window,
                                           std::vector<MissColours>* changes) const {
  // A frame's misses take the mean colours of the window's frames lit as it is (the surfaces
  // both show reflecting the same light to kSameLight, either way), over those with misses in
  // each group: the view decides which surroundings a border shows, and the frames lit alike
  // agree on them; a frame lit otherwise (a flash, a lamp switched on) keeps its own colours
  // and lends them to no other.
  constexpr double kSameLight = 1.25;
  const std::size_t n = window.size();
  const auto levels = [](const TracedLight& t) {
    return !t.miss_shares.empty() && t.reflected.channels() == 3;
  };
  std::vector<char> alike(n * n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    alike[i * n + i] = 1;
    for (std::size_t j = i + 1; j < n; ++j) {
      if (!levels(*window[i]) || !levels(*window[j])) continue;
      const double ratio = detail::shared_light_ratio(window[i]->grid, window[i]->reflected,
                                                      window[j]->grid, window[j]->reflected);
      alike[i * n + j] = alike[j * n + i] = ratio <= kSameLight && ratio * kSameLight >= 1.0;
    }
  }
  std::vector<Image> out;
  if (changes) changes->assign(n, MissColours{});
  for (std::size_t i = 0; i < n; ++i) {
    const TracedLight* t = window[i];
    Image light = t->light;
    MissColours delta{};
    bool any = false;
    if (levels(*t))
      for (int g = 0; g < 3; ++g) {
        if (!(t->miss_weight[g] > 0)) continue;
        double sum[3] = {};
        int count = 0;
        for (std::size_t j = 0; j < n; ++j) {
          if (!alike[i * n + j] || !(window[j]->miss_weight[g] > 0)) continue;
          for (int c = 0; c < 3; ++c) sum[c] += window[j]->miss_colours[g][c];
          ++count;
        }
        for (int c = 0; c < 3; ++c)
          delta[g][c] = static_cast<float>(sum[c] / count - t->miss_colours[g][c]);
        any = any || count > 1;
      }
    if (changes && any) (*changes)[i] = delta;
    if (any)
      detail::parallel_for_rows(light.height(), [&](int y) {
        const std::size_t row = static_cast<std::size_t>(y) * light.width();
        for (int x = 0; x < light.width(); ++x) {
          const std::size_t s = row + x;
          for (int c = 0; c < 3; ++c) {
            float d = 0;
            for (int g = 0; g < 3; ++g) d += t->miss_shares.plane(g)[s] * delta[g][c];
            light.plane(c)[s] = std::max(light.plane(c)[s] + d, 0.0f);
          }
        }
      });
    out.push_back(std::move(light));
  }
  return out;
}

Image Pipeline::finish_coverage(const GBuffer& g, const GBuffer& grid,
                                const Image& grid_coverage) const {
  return detail::coverage_to_frame(grid_coverage, grid.depth, grid.normal, impl_->plan.trace_scale,
                                   static_cast<float>(impl_->settings.thickness), g.depth);
}

Image Pipeline::finish_light(const GBuffer& g, const Image& grid_light) const {
  const int level = pyramid_level(impl_->plan.trace_scale);
  if (level == 0) return grid_light;
  return detail::upsample_and_denoise(grid_light, level, g.depth, g.normal,
                                      impl_->settings.denoise_settings, false);
}

Image Pipeline::indirect_light(const GBuffer& g, Image* coverage) const {
  // Without a temporal stage in between, one pass of the pyramid filters and upsamples (its
  // guides are built once): finish_light(trace_light(g)) but for the 1e-3 own-value fallback
  // of pixels no coarse sample resembles, which takes the traced light here, the filtered one
  // there.
  const Plan& plan = impl_->plan;
  const int level = pyramid_level(plan.trace_scale);
  GBuffer grid;
  Image light = impl_->trace(g, coverage ? &grid : nullptr, coverage);
  if (coverage) *coverage = finish_coverage(g, grid, *coverage);
  if (level == 0 && !plan.denoise) return light;
  return detail::upsample_and_denoise(light, level, g.depth, g.normal,
                                      impl_->settings.denoise_settings, plan.denoise);
}

bool Pipeline::continue_light(const GBuffer& g, const std::vector<const TracedLight*>& window,
                              int center, Image* light, Image* coverage, Image* miss_shares) const {
  std::vector<const detail::FrameTrace*> frames;
  std::vector<const Image*> lights;
  int c = -1;
  for (int i = 0; i < static_cast<int>(window.size()); ++i) {
    if (!window[i]->trace) continue;
    if (i == center) c = static_cast<int>(frames.size());
    frames.push_back(window[i]->trace.get());
    lights.push_back(&window[i]->light);
  }
  if (c < 0) return false;
  detail::ContinuationReport report;
  Image shares;
  const bool continued = detail::continue_rays(frames, lights, c, impl_->settings, light, coverage,
                                               miss_shares ? &shares : nullptr, &report);
  log_info(report.describe(frames[c]->frame));
  if (!continued) return false;
  *light = impl_->denoise_on_grid(g, std::move(*light));  // as trace_light's
  if (miss_shares && shares.channels() == detail::kCubeFaces)
    *miss_shares = impl_->denoise_on_grid(g, grouped_shares(shares));
  return true;
}

std::string Pipeline::describe_misses(const GBuffer& g) const {
  return detail::MissModel(g, impl_->settings.miss, impl_->env).describe();
}

FrameResult Pipeline::composite(const GBuffer& g, Image indirect, Image coverage) const {
  return detail::composite_frame(g, std::move(indirect), std::move(coverage));
}

}  // namespace ssgi
