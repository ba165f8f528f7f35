// ssgi info: what a sequence holds and what `ssgi run` would do with it.
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "run_options.h"
#include "ssgi/layout.h"
#include "ssgi/pipeline.h"
#include "ssgi/threads.h"

namespace ssgi_cli {
namespace {

void print_help() {
  std::printf(
      "usage: ssgi info INPUT [options]\n\n"
      "Prints the resolution, windows, frames, detected layout and channels, cameras and\n"
      "the processing plan. Accepts every option of 'ssgi run' (the plan depends on them).\n\n"
      "%s",
      common_options_help());
}

// "1-6", "1-9x2", "1,4,7-9": frames as compact ranges.
std::string frame_ranges(const std::vector<int>& frames) {
  std::string out;
  for (std::size_t i = 0; i < frames.size();) {
    std::size_t j = i;
    while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
    if (!out.empty()) out += ",";
    out += std::to_string(frames[i]);
    if (j > i) out += "-" + std::to_string(frames[j]);
    i = j + 1;
  }
  return out;
}

std::string window_string(const ssgi::Box2i& b) {
  return "(" + std::to_string(b.x0) + "," + std::to_string(b.y0) + ")-(" +
         std::to_string(b.x1 - 1) + "," + std::to_string(b.y1 - 1) + ")";
}

}  // namespace

int run_info(int argc, char** argv) {
  const CommonOptions o = parse_common_options(argc, argv, /*need_output=*/false);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  install_log_handler(o.verbose, o.quiet);
  const ssgi::ThreadLimit threads(o.threads);
  const ssgi::InputOptions& in = o.run.input;
  const ssgi::SequenceInfo seq = ssgi::open_sequence(in);
  const ssgi::Layout& layout = seq.layout;
  const ssgi::LayoutPreset& preset = layout.preset;
  // Bad option values fail before anything is printed; input problems (no camera, no direct
  // light) are reported in their place and the report goes on, then exit with the first one.
  std::optional<ssgi::Error> problem;
  std::optional<ssgi::Plan> plan;
  try {
    plan = ssgi::make_plan(seq, o.run.gi);
  } catch (const ssgi::Error& e) {
    if (e.kind() == ssgi::ErrorKind::kUsage) throw;
    problem = e;
  }

  std::printf("sequence:      %s\n", in.pattern.c_str());
  std::printf("frames:        %s (%zu to write, %zu on disk)\n", frame_ranges(seq.frames).c_str(),
              seq.frames.size(), seq.frames_on_disk.size());
  std::printf("resolution:    %dx%d\n", seq.display_window.width(), seq.display_window.height());
  std::printf("display window %s\n", window_string(seq.display_window).c_str());
  std::printf("data window    %s%s\n", window_string(seq.data_window).c_str(),
              seq.data_window == seq.display_window ? "" : " (differs from the display window)");
  std::printf("layout:        %s (%s)\n", preset.name.c_str(), preset.renderer.c_str());
  if (!layout.detected_because.empty())
    std::printf("               %s\n", layout.detected_because.c_str());
  std::printf(
      "conventions:   depth %s, background >= %g; normals in %s space; direct light %s "
      "albedo\n",
      ssgi::depth_kind_name(preset.depth_kind), preset.background_depth,
      ssgi::normal_space_name(preset.normal_space),
      preset.direct_includes_albedo ? "includes" : "excludes");
  std::printf("channels:\n");
  for (int r = 0; r < ssgi::kRoleCount; ++r) {
    const auto role = static_cast<ssgi::Role>(r);
    std::string names;
    for (const ssgi::ChannelRef& c : layout.channels(role)) {
      if (!names.empty()) names += ", ";
      const std::string& part = seq.channels.subimage_names[c.subimage];
      names += (seq.channels.subimage_names.size() > 1 && !part.empty() ? part + ":" : "") + c.name;
    }
    std::printf("  %-10s   %s\n", ssgi::role_name(role), names.empty() ? "-" : names.c_str());
  }
  std::printf("cameras:\n");
  for (int f : seq.frames) {
    try {
      const ssgi::Camera cam = ssgi::read_camera(seq, f, in);
      std::printf("  frame %-6d %s, horizontal fov %.4f deg\n", f, cam.source.c_str(),
                  cam.hfov_deg(seq.display_window.width()));
    } catch (const ssgi::Error& e) {
      std::printf("  frame %-6d none: %s\n", f, e.what());
      if (!problem) problem = e;
    }
  }
  std::printf("plan:\n");
  if (plan) {
    for (const std::string& reason : plan->reasons) std::printf("  %s\n", reason.c_str());
  } else {
    std::printf("  cannot run: %s\n", problem->what());
  }
  std::fflush(stdout);
  if (problem) throw *problem;
  return kExitOk;
}

}  // namespace ssgi_cli
