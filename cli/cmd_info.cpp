// ssgi info: what a sequence holds and what `ssgi run` would do with it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "io/camera.h"
#include "io/color.h"
#include "io/frame_reader.h"
#include "io/input_frame.h"
#include "io/layout.h"
#include "io/views.h"
#include "log.h"
#include "memory_plan.h"
#include "options/run_options.h"
#include "plan.h"
#include "settings.h"
#include "simd.h"
#include "ssgi/pipeline.h"
#include "threads.h"

namespace ssgi_cli {
namespace {

using Json = nlohmann::ordered_json;

void print_help() {
  std::printf(
      "usage: ssgi info INPUT [options]\n\n"
      "Prints the resolution, windows, frames, detected layout and channels, cameras,\n"
      "the processing plan and the run's estimated peak memory for the options given\n"
      "(those of 'ssgi run': the plan and the memory depend on them).\n\n"
      "%s",
      options_help(kInfoCommand).c_str());
}

std::string window_string(const ssgi::Box2i& b) {
  return "(" + std::to_string(b.x0) + "," + std::to_string(b.y0) + ")-(" +
         std::to_string(b.x1 - 1) + "," + std::to_string(b.y1 - 1) + ")";
}

// A camera's position and forward direction in world space.
void camera_pose(const ssgi::Camera& c, Imath::V3d* position, Imath::V3d* direction) {
  const Imath::M44d to_world = ssgi::inverse_checked(c.world_to_camera);
  *position = {to_world[3][0], to_world[3][1], to_world[3][2]};
  *direction = Imath::V3d(to_world[2][0], to_world[2][1], to_world[2][2]).normalized();
}

const char* projection_name(ssgi::Projection p) {
  return p == ssgi::Projection::kLatLong ? "lat-long" : "pinhole";
}

std::string vector_text(const Imath::V3d& v) {
  // Float matrices leave values like 1e-17 where a component is 0.
  const auto clean = [](double x) { return std::fabs(x) < 1e-9 ? 0.0 : x; };
  char text[96];
  std::snprintf(text, sizeof text, "(%.4g, %.4g, %.4g)", clean(v.x), clean(v.y), clean(v.z));
  return text;
}

// What `info` found, gathered once and printed as text or JSON.
struct Report {
  std::vector<std::string> role_channels[ssgi::kRoleCount];  // "part:name" in multi-part files
  struct FrameCamera {
    int frame;
    std::optional<ssgi::Camera> camera;
    std::string error;
  };
  std::vector<FrameCamera> cameras;
  // Each view (--view, --latlong-view) as the first frame reads it.
  struct View {
    std::string file;
    const ssgi::ViewInfo* info = nullptr;
    std::optional<ssgi::Camera> camera;
    std::string error;
    Imath::V3d position{0, 0, 0}, direction{0, 0, 0};
    double from_shot = 0;  // distance of its camera from the shot's (world units)
    bool at_shot = false;  // at the shot camera's position (to float precision)
  };
  std::vector<View> views;
  // The first frame's normal pass and the space it is read in (GBuffer::normals_source); empty
  // when the normals come from the depth or the frame could not be read.
  std::string normals;
  std::string preset;                                         // --preset, resolved
  std::vector<std::pair<std::string, std::string>> settings;  // with the options applied
  std::optional<ssgi::Plan> plan;
  std::optional<ssgi::MemoryPlan> memory;  // as run plans it; none without a plan
  std::optional<ssgi::Error> problem;      // the first input problem, reported last
  // --check: each frame decoded as run would (error empty when it read), and the environment.
  struct FrameCheck {
    int frame;
    std::string file, error;
    std::string misses;  // what the miss model decides for it (read frames, a pipeline)
  };
  std::optional<std::vector<FrameCheck>> checks;
  std::string environment_error;
  ssgi::ThreadBudget threads;             // how many worker threads a run would use, and why
  std::string simd;                       // the kernels' instruction set
  std::vector<std::string> simd_targets;  // what --simd accepts here
};

Json window_json(const ssgi::Box2i& b) {
  return Json{{"x_min", b.x0}, {"y_min", b.y0}, {"x_max", b.x1 - 1}, {"y_max", b.y1 - 1}};
}

// "file: what", as the error line names it.
std::string error_text(const ssgi::Error& e) {
  return e.file().empty() ? e.what() : e.file() + ": " + e.what();
}

// The run's memory plan: null without a plan.
Json memory_json(const Report& r) {
  if (!r.memory) return nullptr;
  const ssgi::MemoryPlan& m = *r.memory;
  return {{"estimated_peak_bytes", m.estimate.bytes},
          {"estimated_peak", ssgi::memory_size_text(m.estimate.bytes)},
          {"parts", m.estimate.parts},
          {"limit", m.limit.bytes ? Json({{"bytes", m.limit.bytes}, {"from", m.limit.source}})
                                  : Json(nullptr)},
          {"frames_in_flight", m.memory.frames_in_flight},
          {"frames_in_flight_asked", m.frames_in_flight_asked},
          {"read_twice", m.memory.read_twice},
          {"refused", m.over_limit()}};
}

// --check's findings: null without it.
Json check_json(const Report& r) {
  if (!r.checks) return nullptr;
  Json failed = Json::array(), misses = Json::array();
  for (const Report::FrameCheck& c : *r.checks) {
    if (!c.error.empty())
      failed.push_back({{"frame", c.frame}, {"file", c.file}, {"error", c.error}});
    else if (!c.misses.empty())
      misses.push_back({{"frame", c.frame}, {"misses", c.misses}});
  }
  return {{"frames", r.checks->size()},
          {"read", r.checks->size() - failed.size()},
          {"failed", failed},
          {"misses", misses},
          {"environment", r.environment_error.empty() ? Json("ok") : Json(r.environment_error)}};
}

Json views_json(const ssgi::SequenceInfo& seq, const Report& r) {
  Json out = Json::array();
  for (const Report::View& v : r.views) {
    const ssgi::SequenceInfo& vs = *v.info->sequence;
    Json view = {{"file", v.file},
                 {"pattern", v.info->pattern},
                 {"still", v.info->still},
                 {"resolution", {vs.display_window.width(), vs.display_window.height()}},
                 {"projection", projection_name(v.info->projection)}};
    if (v.camera) {
      view["camera"] = {{"frame", seq.frames.front()},
                        {"source", v.camera->source},
                        {"position", {v.position.x, v.position.y, v.position.z}},
                        {"direction", {v.direction.x, v.direction.y, v.direction.z}},
                        {"hfov_deg", v.camera->hfov_deg(vs.display_window.width())}};
      view["distance_from_shot_camera"] = v.from_shot;
      view["at_shot_camera"] = v.at_shot;
    } else {
      view["error"] = v.error;
    }
    out.push_back(std::move(view));
  }
  return out;
}

void print_json(const ssgi::InputOptions& in, const ssgi::SequenceInfo& seq, const Report& r) {
  const ssgi::LayoutPreset& preset = seq.layout.preset;
  Json channels = Json::object();
  for (int k = 0; k < ssgi::kRoleCount; ++k)
    channels[ssgi::role_name(static_cast<ssgi::Role>(k))] = r.role_channels[k];
  Json settings = Json::object();
  for (const auto& [name, value] : r.settings) settings[name] = value;
  Json cameras = Json::array();
  for (const Report::FrameCamera& c : r.cameras) {
    if (c.camera) {
      Json camera = {{"frame", c.frame},
                     {"source", c.camera->source},
                     {"hfov_deg", c.camera->hfov_deg(seq.display_window.width())}};
      if (c.camera->fit_residual_px) camera["fit_residual_px"] = *c.camera->fit_residual_px;
      cameras.push_back(std::move(camera));
    } else
      cameras.push_back({{"frame", c.frame}, {"error", c.error}});
  }
  Json out = {
      {"sequence", in.pattern},
      {"frames", seq.frames},
      {"frames_on_disk", seq.frames_on_disk},
      {"resolution", {seq.display_window.width(), seq.display_window.height()}},
      {"display_window", window_json(seq.display_window)},
      {"data_window", window_json(seq.data_window)},
      {"context", seq.context ? Json({{"sequence", in.context},
                                      {"data_window", window_json(seq.context->data_window)}})
                              : Json(nullptr)},
      {"layout",
       {{"name", preset.name},
        {"renderer", preset.renderer},
        {"detected_because", seq.layout.detected_because},
        {"depth_kind", ssgi::depth_kind_name(preset.depth_kind)},
        {"background_depth", preset.background_depth},
        {"normal_space", ssgi::normal_space_name(preset.normal_space)},
        {"direct_includes_albedo", preset.direct_includes_albedo},
        {"channels", channels}}},
      {"cameras", cameras},
      {"views", views_json(seq, r)},
      {"normals", r.normals.empty() ? Json(nullptr)
                                    : Json({{"frame", seq.frames.front()}, {"source", r.normals}})},
      {"preset", r.preset},
      {"settings", settings},
      {"threads", {{"count", r.threads.threads}, {"from", r.threads.source}}},
      {"memory", memory_json(r)},
      {"simd", {{"target", r.simd}, {"available", r.simd_targets}}},
      {"plan", r.plan ? Json(r.plan->reasons) : Json(nullptr)},
      {"check", check_json(r)},
      {"error", r.problem ? Json(error_text(*r.problem)) : Json(nullptr)},
  };
  std::printf("%s\n", out.dump(2).c_str());
}

// The run's memory plan, the first line as run -v logs it.
void print_memory(const Report& r) {
  if (!r.memory) {
    std::printf("memory:        not estimated: the plan cannot be made\n");
    return;
  }
  const ssgi::MemoryPlan& m = *r.memory;
  std::printf("memory:        estimated peak %s; limit %s\n",
              ssgi::memory_size_text(m.estimate.bytes).c_str(),
              ssgi::memory_limit_text(m.limit).c_str());
  std::printf("  parts          %s\n", m.estimate.parts.c_str());
  const int in_flight = m.memory.frames_in_flight;
  std::printf("  in flight      %d frame%s read, lit and written at once", in_flight,
              in_flight == 1 ? "" : "s");
  std::printf(" (%s)\n", m.reason().c_str());
  std::printf("  decoded        %s\n", m.memory.read_twice
                                           ? "twice a frame (lit, then finished and written)"
                                           : "once a frame");
  if (m.over_limit())
    std::printf("  refused        over the limit: ssgi run would refuse the run (exit 3)\n");
}

void print_text(const ssgi::InputOptions& in, const ssgi::SequenceInfo& seq, const Report& r) {
  const ssgi::Layout& layout = seq.layout;
  const ssgi::LayoutPreset& preset = layout.preset;
  std::printf("sequence:      %s\n", in.pattern.c_str());
  std::printf("frames:        %s (%zu to write, %zu on disk)\n", frame_ranges(seq.frames).c_str(),
              seq.frames.size(), seq.frames_on_disk.size());
  std::printf("resolution:    %dx%d\n", seq.display_window.width(), seq.display_window.height());
  std::printf("display window %s\n", window_string(seq.display_window).c_str());
  std::printf("data window    %s%s\n", window_string(seq.data_window).c_str(),
              seq.data_window == seq.display_window ? "" : " (differs from the display window)");
  if (seq.context)
    std::printf("context:       %s, data window %s\n", in.context.c_str(),
                window_string(seq.context->data_window).c_str());
  std::printf("layout:        %s (%s)\n", preset.name.c_str(), preset.renderer.c_str());
  if (!layout.detected_because.empty())
    std::printf("               %s\n", layout.detected_because.c_str());
  std::printf(
      "conventions:   depth %s, background >= %g; %s; direct light %s albedo\n",
      ssgi::depth_kind_name(preset.depth_kind), preset.background_depth,
      preset.normal_space == ssgi::NormalSpace::kAuto
          ? "normals' space decided per frame by the depth"
          : (std::string("normals in ") + ssgi::normal_space_name(preset.normal_space) + " space")
                .c_str(),
      preset.direct_includes_albedo ? "includes" : "excludes");
  std::printf("channels:\n");
  for (int k = 0; k < ssgi::kRoleCount; ++k) {
    std::string names;
    for (const std::string& c : r.role_channels[k]) names += (names.empty() ? "" : ", ") + c;
    std::printf("  %-10s   %s\n", ssgi::role_name(static_cast<ssgi::Role>(k)),
                names.empty() ? "-" : names.c_str());
  }
  std::printf("cameras:\n");
  for (const Report::FrameCamera& c : r.cameras) {
    if (c.camera)
      std::printf("  frame %-6d %s, horizontal fov %.4f deg\n", c.frame, c.camera->source.c_str(),
                  c.camera->hfov_deg(seq.display_window.width()));
    else
      std::printf("  frame %-6d none: %s\n", c.frame, c.error.c_str());
  }
  if (!r.views.empty()) std::printf("views (frame %d):\n", seq.frames.front());
  for (const Report::View& v : r.views) {
    const ssgi::SequenceInfo& vs = *v.info->sequence;
    const int w = vs.display_window.width(), h = vs.display_window.height();
    std::printf("  %s%s: %dx%d %s", v.file.c_str(), v.info->still ? " (still)" : "", w, h,
                projection_name(v.info->projection));
    if (v.info->projection == ssgi::Projection::kLatLong)
      std::printf(" (six cube faces of %d)", ssgi::detail::latlong_face_size(vs.display_window));
    if (!v.camera) {
      std::printf(", no camera: %s\n", v.error.c_str());
      continue;
    }
    std::printf("\n    camera %s at %s looking along %s, horizontal fov %.4f deg\n",
                v.camera->source.c_str(), vector_text(v.position).c_str(),
                vector_text(v.direction).c_str(), v.camera->hfov_deg(w));
    if (v.at_shot)
      std::printf("    at the shot camera's position\n");
    else
      std::printf(
          "    %.4g from the shot camera's position: rays continue in it all the same, "
          "parallax-correct\n",
          v.from_shot);
  }
  if (!r.normals.empty())
    std::printf("normals:       frame %d: %s\n", seq.frames.front(), r.normals.c_str());
  std::printf("settings (preset %s):\n", r.preset.c_str());
  for (const auto& [name, value] : r.settings)
    std::printf("  %-14s %s\n", name.c_str(), value.c_str());
  std::printf("threads:       %d (%s)\n", r.threads.threads, r.threads.source.c_str());
  print_memory(r);
  std::string targets;
  for (const std::string& t : r.simd_targets) targets += (targets.empty() ? "" : ", ") + t;
  std::printf("simd:          %s (--simd: %s)\n", r.simd.c_str(), targets.c_str());
  if (r.checks) {
    std::size_t read = 0;
    for (const Report::FrameCheck& c : *r.checks) read += c.error.empty();
    std::printf("check:         %zu of %zu frames read as run reads them%s\n", read,
                r.checks->size(),
                r.environment_error.empty() ? "" : "; the environment map cannot be used");
    for (const Report::FrameCheck& c : *r.checks)
      if (!c.error.empty())
        std::printf("  frame %-6d %s: %s\n", c.frame, c.file.c_str(), c.error.c_str());
    for (const Report::FrameCheck& c : *r.checks)
      if (!c.misses.empty()) std::printf("  frame %-6d %s\n", c.frame, c.misses.c_str());
    if (!r.environment_error.empty()) std::printf("  %s\n", r.environment_error.c_str());
  }
  std::printf("plan:\n");
  if (r.plan) {
    for (const std::string& reason : r.plan->reasons) std::printf("  %s\n", reason.c_str());
  } else {
    std::printf("  cannot run: %s\n", r.problem->what());
  }
}

}  // namespace

int run_info(int argc, char** argv) {
  const CommonOptions o = parse_common_options(kInfoCommand, argc, argv, /*need_output=*/false);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  install_log_handler(o.verbose, o.quiet);
  const ssgi::ThreadLimit threads(o.threads);
  const ssgi::InputOptions& in = o.run.input;
  ssgi::SequenceInfo seq;
  try {
    seq = ssgi::open_sequence(in);
  } catch (const ssgi::Error& e) {
    // With --json a machine still gets a document: the error alone.
    if (o.json && e.kind() != ssgi::ErrorKind::kUsage)
      std::printf("%s\n", Json{{"error", error_text(e)}}.dump(2).c_str());
    throw;
  }
  // Bad option values fail before anything is printed; input problems (no camera, no direct
  // light) are reported in their place and the report goes on, then exit with the first one.
  Report r;
  r.threads = threads.budget();
  r.simd = ssgi::simd_target();
  r.simd_targets = ssgi::simd_targets();
  r.preset = o.preset;
  r.settings = ssgi::describe_settings(o.run.gi);
  try {
    r.plan = ssgi::make_plan(seq, o.run.gi);
    r.memory = ssgi::plan_run_memory(seq, o.run.gi, o.run.write, o.run.memory_limit,
                                     o.run.frames_in_flight);
    for (const std::string& warning : r.plan->warnings) ssgi::log_warning(warning);
    // What the run's colour management would decide (the config is loaded, nothing converted).
    const ssgi::ColorManagement color = ssgi::color_management_for(o.run.gi.color, seq);
    for (const std::string& reason : color.reasons()) r.plan->reasons.push_back(reason);
  } catch (const ssgi::Error& e) {
    if (e.kind() == ssgi::ErrorKind::kUsage) throw;
    r.problem = e;
  }
  const bool multipart = seq.channels.subimage_names.size() > 1;
  for (int k = 0; k < ssgi::kRoleCount; ++k) {
    for (const ssgi::ChannelRef& c : seq.layout.channels(static_cast<ssgi::Role>(k))) {
      const std::string& part = seq.channels.subimage_names[c.subimage];
      r.role_channels[k].push_back((multipart && !part.empty() ? part + ":" : "") + c.name);
    }
  }
  for (int f : seq.frames) {
    try {
      r.cameras.push_back({f, ssgi::read_camera(seq, f, in), {}});
    } catch (const ssgi::Error& e) {
      r.cameras.push_back({f, std::nullopt, e.what()});
      if (!r.problem) r.problem = e;
    }
  }
  for (const ssgi::ViewInfo& view : seq.views) {
    Report::View v;
    v.info = &view;
    v.file = view.path_for(seq.frames.front());
    ssgi::InputOptions o = in;
    o.camera = ssgi::CameraOptions();
    o.camera.projection = view.projection;
    try {
      v.camera = ssgi::read_camera(*view.sequence, view.sequence->frames.front(), o);
      camera_pose(*v.camera, &v.position, &v.direction);
      if (!r.cameras.empty() && r.cameras.front().camera &&
          r.cameras.front().camera->has_world_transform) {
        Imath::V3d shot_position, shot_direction;
        camera_pose(*r.cameras.front().camera, &shot_position, &shot_direction);
        v.from_shot = (v.position - shot_position).length();
        // Matrices written as floats: positions agree to a few parts in 1e7 of their size.
        v.at_shot =
            v.from_shot <= 1e-5 * std::max({1.0, shot_position.length(), v.position.length()});
      }
    } catch (const ssgi::Error& e) {
      v.error = e.what();
      if (!r.problem) r.problem = e;
    }
    r.views.push_back(std::move(v));
  }
  if (seq.layout.has(ssgi::Role::kNormal) && !seq.normals_from_depth && !r.cameras.empty() &&
      r.cameras.front().camera) {
    // The first frame's normals as run reads them: the space is the layout's or, for auto, the
    // one that agrees with the depth.
    try {
      const ssgi::RoleMask roles =
          ssgi::role_bit(ssgi::Role::kDepth) | ssgi::role_bit(ssgi::Role::kNormal);
      r.normals = ssgi::read_gbuffer(seq, seq.frames.front(), roles, in).normals_source;
    } catch (const ssgi::Error& e) {
      if (!r.problem) r.problem = e;
    }
  }
  if (o.check) {
    // What run does before computing: the environment map, then each frame's passes.
    r.checks.emplace();
    std::optional<ssgi::Pipeline> pipeline;
    try {
      pipeline.emplace(seq, o.run.gi);
    } catch (const ssgi::Error& e) {
      if (e.kind() == ssgi::ErrorKind::kUsage) throw;
      r.environment_error = error_text(e);
      if (!r.problem) r.problem = e;
    }
    const ssgi::RoleMask roles = r.plan ? r.plan->roles : 0;
    for (int f : seq.frames) {
      Report::FrameCheck c{f, seq.pattern.path_for(f), {}, {}};
      try {
        const ssgi::GBuffer g = ssgi::read_gbuffer(seq, f, roles, in);
        if (pipeline) c.misses = pipeline->describe_misses(g);
      } catch (const ssgi::Error& e) {
        if (!e.file().empty()) c.file = e.file();
        c.error = e.what();
        if (!r.problem) r.problem = e;
      }
      r.checks->push_back(std::move(c));
    }
  }
  if (o.json)
    print_json(in, seq, r);
  else
    print_text(in, seq, r);
  std::fflush(stdout);
  if (r.problem) throw *r.problem;
  return kExitOk;
}

}  // namespace ssgi_cli
