// The plan: which stages run and which channels are read, from the inputs and the settings.
#include "plan.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gi/denoise.h"
#include "settings.h"
#include "throw.h"

namespace ssgi {
namespace {

std::string color_string(const std::array<float, 3>& c) {
  std::ostringstream s;
  s << c[0] << "," << c[1] << "," << c[2];
  return s.str();
}

// A window as OpenEXR states it, inclusive: (x0,y0)-(x1,y1).
std::string corners(const Box2i& b) {
  return "(" + std::to_string(b.x0) + "," + std::to_string(b.y0) + ")-(" +
         std::to_string(b.x1 - 1) + "," + std::to_string(b.y1 - 1) + ")";
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
  // A region render: what is lit (the data window, or the context's) lacks part of the picture.
  const bool cropped = !seq.working_window().contains(seq.display_window);
  if (cropped && (s.miss == MissMode::kAuto || s.miss == MissMode::kFrame))
    misses +=
        "; a region render: the part of the display window's border it lacks brings no light "
        "(a fraction of the whole frame's light)";
  plan.reasons.push_back(misses);
  if (cropped && !seq.context)
    plan.warnings.push_back(
        seq.pattern.path_for(seq.frames.front()) + ": the data window " + corners(seq.data_window) +
        " is a region of the display window " + corners(seq.display_window) +
        ": its rays see only the region, which gets a fraction of the whole frame's light there; "
        "give the whole frames it was cut from with --context");
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
  if (!seq.views.empty()) {
    if (s.tracer != Tracer::kSlices) {
      plan.warnings.push_back(
          "--view: the views are not used: only the slice tracer's missed "
          "rays continue in them (--tracer slices)");
      plan.reasons.push_back("views: off (the slice tracer's misses only)");
    } else {
      plan.views = true;
      std::size_t pinhole = 0, latlong = 0;
      for (const ViewInfo& v : seq.views)
        ++(v.projection == Projection::kLatLong ? latlong : pinhole);
      std::string which;
      if (pinhole) which = std::to_string(pinhole) + (pinhole == 1 ? " view" : " views");
      if (latlong)
        which += (which.empty() ? "" : " and ") + std::to_string(latlong) +
                 (latlong == 1 ? " lat-long view (six cube faces)"
                               : " lat-long views (six cube faces each)");
      plan.reasons.push_back(
          "views: missed rays continued in " + which +
          ", each lit as a frame is (its own rays, misses and bounces, continued in the others), "
          "the nearest surface any of them shows on a ray taken" +
          (plan.multiframe ? "; what they miss goes on to the other frames (multiframe)" : ""));
    }
  }
  if (seq.guide) {
    if (plan.temporal == TemporalMode::kEma)
      throw_usage(
          "--guide: the guide is filtered over the symmetric temporal window or over each frame "
          "alone: use --temporal window or none with it, not ema");
    plan.guide = true;
    const int f = seq.guide->fraction;
    plan.reasons.push_back(
        "guide: " + seq.guide->pattern + " (" +
        (f == 1 ? std::string("the shot's resolution") : "1/" + std::to_string(f) + " of it") +
        "), its " + seq.guide->sequence->layout.preset.name +
        " indirect light with ssgi's as its control variate: their difference filtered" +
        (plan.temporal == TemporalMode::kWindow ? " over the window and" : "") +
        " over the surface, kept as it is where it stands out of the guide's noise");
  }
  plan.reasons.push_back("composite: direct + emission + albedo x indirect");
  return plan;
}

}  // namespace ssgi
