// Presets and the settings as text.
#include "settings.h"

#include <charconv>
#include <cstdlib>

#include "throw.h"

namespace ssgi {
namespace {

// A preset is a row: the tracing settings it sets, nothing else.
struct PresetRow {
  const char* name;
  int slices, max_steps, trace_width, bounces, multiframe;
};

// Time against error, measured in tests/sweep/README.md (the sample scenes) and
// tests/bench/README.md, "GI per frame" (1080p, with --multiframe's cost). final also continues
// missed rays through the window's other frames: a cost a final render affords, not the default.
constexpr PresetRow kPresets[] = {
    {"draft", 1, 16, 240, 4, 0},
    {"default", 2, 28, 480, 8, 0},
    {"final", 4, 28, 480, 8, kMultiframeWindow},
};

// The shortest text that reads back as the same value (0.1f is "0.1"), so that two settings
// that differ never print alike: the output's provenance compares them as text.
template <typename T>
std::string text(const T& v) {
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return ec == std::errc() ? std::string(buffer, end) : std::string("?");
}

}  // namespace

std::string multiframe_text(int multiframe) {
  if (multiframe <= 0) return "off";
  if (multiframe >= kMultiframeWindow) return "on";
  return "on:" + text(multiframe);
}

std::string temporal_text(const GiSettings& s) {
  const std::string name = enum_name(kTemporalModeNames, s.temporal);
  switch (s.temporal) {
    case TemporalMode::kNone:
      return name;
    case TemporalMode::kEma:
      return name + ":" + text(s.ema_alpha);
    case TemporalMode::kWindow:
      return name + ":" + text(s.temporal_radius);
  }
  return name;
}

const char* miss_mode_name(MissMode mode) { return enum_name(kMissModeNames, mode); }

void apply_preset(const std::string& name, GiSettings* s) {
  for (const PresetRow& row : kPresets) {
    if (name != row.name) continue;
    s->tracer = Tracer::kSlices;
    s->slices = row.slices;
    s->max_steps = row.max_steps;
    s->trace_scale = 0;
    s->trace_width = row.trace_width;
    s->bounces = row.bounces;
    s->multiframe = row.multiframe;
    return;
  }
  throw_usage("unknown --preset '" + name + "' (draft, default, final)");
}

const std::vector<std::string>& preset_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const PresetRow& row : kPresets) n.push_back(row.name);
    return n;
  }();
  return names;
}

std::vector<std::pair<std::string, std::string>> describe_settings(const GiSettings& s) {
  std::vector<std::pair<std::string, std::string>> out = {
      {"tracer", enum_name(kTracerNames, s.tracer)}};
  if (s.tracer == Tracer::kSlices) {
    out.emplace_back("slices", text(s.slices));
    out.emplace_back("max-steps", text(s.max_steps));
    out.emplace_back("trace-scale", s.trace_scale ? text(s.trace_scale)
                                                  : "auto (" + text(s.trace_width) + " across)");
  } else {
    out.emplace_back("rays", text(s.rays));
    if (s.tracer == Tracer::kScreenSpace) out.emplace_back("max-steps", text(s.max_steps));
  }
  out.emplace_back("bounces", text(s.bounces));
  out.emplace_back("thickness", text(s.thickness));
  out.emplace_back("start-offset", text(s.start_offset));
  out.emplace_back("max-distance", text(s.max_distance));
  out.emplace_back("miss", miss_mode_name(s.miss));
  out.emplace_back("env", s.env_map.empty() ? text(s.env_color[0]) + "," + text(s.env_color[1]) +
                                                  "," + text(s.env_color[2])
                                            : s.env_map);
  if (!s.env_map.empty()) out.emplace_back("env-up", std::string(1, s.env_up));
  out.emplace_back("gather-emission", s.gather_emission < 0    ? "layout"
                                      : s.gather_emission == 0 ? "no"
                                                               : "yes");
  out.emplace_back("denoise", enum_name(kDenoiseModeNames, s.denoise));
  if (s.denoise == DenoiseMode::kPyramid) {
    const DenoiseSettings& d = s.denoise_settings;
    out.emplace_back("denoise-radius", text(d.radius));
    out.emplace_back("denoise-sigma-spatial", text(d.sigma_spatial));
    out.emplace_back("denoise-sigma-depth", text(d.sigma_depth));
    out.emplace_back("denoise-normal-power", text(d.normal_power));
    out.emplace_back("denoise-blur", text(d.upsample_blur_radius));
  }
  out.emplace_back("temporal", temporal_text(s));
  // Only when on, so that outputs written before the option existed still match.
  if (s.multiframe) out.emplace_back("multiframe", multiframe_text(s.multiframe));
  out.emplace_back("seed", text(s.seed));
  // The colour spaces as given (the config by its path): the output's pixels depend on them.
  const ColorSettings& c = s.color;
  const std::string config = color_config_path(c);
  out.emplace_back("colorconfig", config.empty() ? "none" : config);
  if (!config.empty()) {
    out.emplace_back("input-colorspace", c.input.empty() ? "auto" : c.input);
    out.emplace_back("output-colorspace", c.output.empty() ? "working" : c.output);
    out.emplace_back("env-colorspace", c.env.empty() ? "auto" : c.env);
    out.emplace_back("working-space", c.working.empty() ? "scene_linear" : c.working);
  }
  return out;
}

std::string color_config_path(const ColorSettings& settings) {
  if (!settings.config.empty()) return settings.config;
  const char* env = std::getenv("OCIO");
  return env ? env : "";
}

}  // namespace ssgi
