// ssgi sweep: every preset (and a small grid of settings) over a shot, each measured against
// the Embree reference of the same frames and against a truth layer of the input, as a table
// (CSV, JSON) and a plot of error against time per frame.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "compare/compare.h"
#include "io/frame_reader.h"
#include "io/temporary_files.h"
#include "options/run_options.h"
#include "settings.h"
#include "ssgi/compare.h"
#include "ssgi/log.h"
#include "sweep_plot.h"
#include "threads.h"
#include "throw.h"
#include "truth_layer.h"

namespace ssgi_cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// The CSV's columns, in order (man/ssgi-sweep.1).
const char* const kColumns[] = {"name",          "settings",   "ms_per_frame",
                                "relrmse_ref",   "psnr_ref",   "ssim_ref",
                                "relrmse_truth", "psnr_truth", "ssim_truth"};

void print_help() {
  std::printf(
      "usage: ssgi sweep INPUT -o TABLE.csv [--presets LIST] [--grid] [--truth LAYER]\n"
      "                  [--json FILE] [--plot FILE.png] [options]\n\n"
      "Runs each preset (and with --grid 12 more settings) over the shot and measures\n"
      "each run's indirect light against ssgi reference on the same frames and, with\n"
      "--truth, against that layer of the input: ms per frame (the frames' gi_ms, mean\n"
      "of the fastest round), relRMSE (RMSE / the mean of what it is measured against),\n"
      "PSNR and SSIM over surface pixels, one row per run. Scratch frames go to a private\n"
      "temporary directory removed at the end.\n\n%s",
      options_help(kSweepCommand).c_str());
}

// One configuration the sweep runs.
struct SweepRun {
  std::string name;
  ssgi::GiSettings gi;
  bool guide = false;  // with the --guide given (the other runs go without it)
};

// The settings presets and the grid change, as one CSV cell without commas.
std::string settings_text(const ssgi::GiSettings& gi) {
  std::string trace = gi.trace_scale == 0 ? "trace-width=" + std::to_string(gi.trace_width)
                                          : "trace-scale=" + std::to_string(gi.trace_scale);
  return "slices=" + std::to_string(gi.slices) + " max-steps=" + std::to_string(gi.max_steps) +
         " " + trace + " bounces=" + std::to_string(gi.bounces);
}

// The presets asked for, then the grid: slices {1, 2, 4} x max-steps {16, 28} x bounces
// {4, 8} over the default preset (its trace grid, misses, denoiser and temporal window).
std::vector<SweepRun> sweep_runs(const CommonOptions& o) {
  std::vector<SweepRun> runs;
  for (const std::string& preset : o.presets) {
    SweepRun r{preset, o.run.gi};
    ssgi::apply_preset(preset, &r.gi);
    runs.push_back(r);
  }
  // With a guide, each preset again with it: the trade a guide makes beside ssgi alone.
  if (!o.run.input.guide.empty()) {
    const std::size_t presets = runs.size();
    for (std::size_t i = 0; i < presets; ++i) {
      SweepRun r = runs[i];
      r.name += "+guide";
      r.guide = true;
      runs.push_back(r);
    }
  }
  if (o.grid) {
    for (int slices : {1, 2, 4}) {
      for (int steps : {16, 28}) {
        for (int bounces : {4, 8}) {
          SweepRun r{"s" + std::to_string(slices) + "-m" + std::to_string(steps) + "-b" +
                         std::to_string(bounces),
                     o.run.gi};
          ssgi::apply_preset("default", &r.gi);
          r.gi.slices = slices;
          r.gi.max_steps = steps;
          r.gi.bounces = bounces;
          runs.push_back(r);
        }
      }
    }
  }
  return runs;
}

// The input's depth channel as compare names it: its background marks the pixels left out.
std::string depth_channel(const ssgi::SequenceInfo& sequence) {
  const std::vector<ssgi::ChannelRef>& refs = sequence.layout.channels(ssgi::Role::kDepth);
  if (refs.empty()) return {};
  const ssgi::ChannelRef& ref = refs.front();
  const auto& parts = sequence.channels.subimage_names;
  if (sequence.channels.channels.size() > 1 && ref.name.find('.') == std::string::npos &&
      ref.subimage < static_cast<int>(parts.size()) && !parts[ref.subimage].empty())
    return parts[ref.subimage] + "." + ref.name;
  return ref.name;
}

// The metrics of one run against one reference, means over the frames.
struct Scores {
  std::optional<double> relrmse, psnr, ssim;
};

Scores scores_of(const std::vector<ssgi::CompareResult>& frames) {
  const ssgi::SequenceSummary s = ssgi::summarize_frames(frames);
  if (s.layers.empty()) return {};
  const auto& m = s.layers.front().metrics;
  return {m[static_cast<int>(ssgi::Metric::kRelRmse)].mean,
          m[static_cast<int>(ssgi::Metric::kPsnr)].mean,
          m[static_cast<int>(ssgi::Metric::kSsim)].mean};
}

// What one configuration measured.
struct SweepRow {
  SweepRun run;
  std::vector<double> gi_ms;     // every frame of every round
  std::vector<double> round_ms;  // each round's gi_ms over its frames, per frame
  Scores ref, truth;
  // The fastest round's mean: a frame's gi_ms includes the neighbours its temporal window
  // traces first (frame 1 traces 1 to 3), so only the sum is the cost of the frames; and a
  // shared machine's noise only ever adds time.
  double ms_per_frame() const {
    return round_ms.empty() ? 0 : *std::min_element(round_ms.begin(), round_ms.end());
  }
};

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0 : sum / v.size();
}

// Runs the sequence; any frame that fails stops the sweep with that frame's error.
ssgi::RunReport run_checked(const ssgi::RunOptions& options) {
  ssgi::RunOptions run = options;
  run.fail_fast = true;
  ssgi::RunReport report = ssgi::run_sequence(run);
  for (const ssgi::FrameReport& f : report.frames)
    if (!f.ok)
      throw ssgi::Error(f.error_kind, f.error_file.empty() ? f.input : f.error_file, f.error);
  return report;
}

std::string number_text(const std::optional<double>& v, const char* format) {
  if (!v) return "";
  if (std::isinf(*v)) return *v > 0 ? "inf" : "-inf";
  char text[64];
  std::snprintf(text, sizeof text, format, *v);
  return text;
}

Json json_number(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_table(const std::vector<SweepRow>& rows) {
  std::string out;
  for (const char* c : kColumns) out += std::string(out.empty() ? "" : ",") + c;
  out += "\n";
  for (const SweepRow& r : rows) {
    const std::vector<std::string> cells = {r.run.name,
                                            settings_text(r.run.gi),
                                            number_text(r.ms_per_frame(), "%.1f"),
                                            number_text(r.ref.relrmse, "%.4f"),
                                            number_text(r.ref.psnr, "%.2f"),
                                            number_text(r.ref.ssim, "%.4f"),
                                            number_text(r.truth.relrmse, "%.4f"),
                                            number_text(r.truth.psnr, "%.2f"),
                                            number_text(r.truth.ssim, "%.4f")};
    std::string line;
    for (const std::string& cell : cells) line += (line.empty() ? "" : ",") + csv_cell(cell);
    out += line + "\n";
  }
  return out;
}

// The time axis' unit, the error axis' meaning and where the numbers came from, in words.
struct Context {
  std::string shot, frames, truth_layer;
  int width = 0, height = 0, spp = 0, repeat = 1, threads = 1;
  double reference_ms = 0;
};

Json json_report(const std::vector<SweepRow>& rows, const std::vector<bool>& front,
                 const Context& c) {
  Json out = {{"shot", c.shot},
              {"frames", c.frames},
              {"resolution", {c.width, c.height}},
              {"threads", c.threads},
              {"repeat", c.repeat},
              {"reference", {{"spp", c.spp}, {"ms_per_frame", c.reference_ms}}},
              {"truth", c.truth_layer.empty() ? Json(nullptr) : Json(c.truth_layer)},
              {"columns", kColumns},
              {"rows", Json::array()}};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SweepRow& r = rows[i];
    Json settings = Json::object();
    for (const auto& [name, value] : ssgi::describe_settings(r.run.gi)) settings[name] = value;
    out["rows"].push_back({{"name", r.run.name},
                           {"settings", settings_text(r.run.gi)},
                           {"ms_per_frame", r.ms_per_frame()},
                           {"relrmse_ref", json_number(r.ref.relrmse)},
                           {"psnr_ref", json_number(r.ref.psnr)},
                           {"ssim_ref", json_number(r.ref.ssim)},
                           {"relrmse_truth", json_number(r.truth.relrmse)},
                           {"psnr_truth", json_number(r.truth.psnr)},
                           {"ssim_truth", json_number(r.truth.ssim)},
                           {"pareto", static_cast<bool>(front[i])},
                           {"round_ms", r.round_ms},
                           {"gi_ms", r.gi_ms},
                           {"all_settings", settings}});
  }
  return out;
}

// The y value of a row in the plot: against the truth when there is one.
std::optional<double> plotted_error(const SweepRow& r, bool truth) {
  return truth ? r.truth.relrmse : r.ref.relrmse;
}

// A line of progress on stderr, unless -q.
void say(const CommonOptions& o, const std::string& line) {
  if (!o.quiet) std::fprintf(stderr, "ssgi: %s\n", line.c_str());
}

std::string ms_text(double ms) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f ms", ms);
  return text;
}

}  // namespace

int run_sweep(int argc, char** argv) {
  const CommonOptions o = parse_common_options(kSweepCommand, argc, argv, /*need_output=*/true);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  install_log_handler(o.verbose, o.quiet);
  const ssgi::ThreadLimit threads(o.threads);
  const std::vector<SweepRun> runs = sweep_runs(o);

  // Everything that can be refused is refused before the first frame is traced.
  const ssgi::SequenceInfo sequence = ssgi::open_sequence(o.run.input);
  // The runs write the frames found now: a gap among them is warned about once, here.
  ssgi::InputOptions input = o.run.input;
  if (input.frames.empty()) input.frames = frame_ranges(sequence.frames);
  // The reference and the runs without a guide read none.
  input.guide.clear();
  const std::string first_input = sequence.pattern.path_for(sequence.frames.front());
  const std::string truth =
      o.truth.empty() ? "" : resolve_truth_layer(sequence.channels, o.truth, first_input);
  const std::string depth = depth_channel(sequence);
  for (const std::string* out : {&o.run.output, &o.json_file, &o.plot}) {
    if (out->empty()) continue;
    std::error_code ec;
    if (fs::is_directory(*out, ec)) ssgi::throw_usage("output '" + *out + "' is a directory");
  }

  const ssgi::TemporaryDirectory scratch("ssgi-sweep-");
  Context context;
  context.shot = o.run.input.pattern;
  context.frames = frame_ranges(sequence.frames);
  context.truth_layer = truth;
  context.width = sequence.data_window.width();
  context.height = sequence.data_window.height();
  context.spp = o.reference_spp;
  context.repeat = o.repeat;
  context.threads = threads.budget().threads;
  say(o, "sweep: " + context.shot + ", frames " + context.frames + ", " +
             std::to_string(runs.size()) + " runs x " + std::to_string(o.repeat) +
             " rounds, against the reference (" + std::to_string(o.reference_spp) +
             " rays per pixel)" + (truth.empty() ? "" : " and " + truth));

  // The reference keeps the input's channels, so that its depth marks the background.
  ssgi::RunOptions reference = subcommand_defaults(kReferenceCommand);
  reference.input = input;
  reference.gi.rays = o.reference_spp;
  reference.output = scratch.path() + "/reference.####.exr";
  const ssgi::RunReport reference_report = run_checked(reference);
  std::vector<double> reference_ms;
  for (const ssgi::FrameReport& f : reference_report.frames) reference_ms.push_back(f.gi_ms);
  context.reference_ms = mean(reference_ms);
  say(o, "reference: " + std::to_string(reference_report.frames.size()) + " frames, " +
             ms_text(context.reference_ms) + " per frame");

  std::vector<SweepRow> rows;
  for (const SweepRun& r : runs) rows.push_back({r, {}, {}, {}, {}});
  for (int round = 0; round < o.repeat; ++round) {
    for (std::size_t i = 0; i < rows.size(); ++i) {
      SweepRow& row = rows[i];
      ssgi::RunOptions run = o.run;
      run.input = input;
      if (row.run.guide) run.input.guide = o.run.input.guide;
      run.gi = row.run.gi;
      run.output = scratch.path() + "/run.####.exr";
      run.write.passthrough = false;
      const ssgi::RunReport report = run_checked(run);
      std::vector<double> round_ms;
      for (const ssgi::FrameReport& f : report.frames) round_ms.push_back(f.gi_ms);
      row.gi_ms.insert(row.gi_ms.end(), round_ms.begin(), round_ms.end());
      row.round_ms.push_back(mean(round_ms));
      std::string line = (o.repeat > 1 ? "round " + std::to_string(round + 1) + "/" +
                                             std::to_string(o.repeat) + ", "
                                       : std::string()) +
                         "run " + std::to_string(i + 1) + "/" + std::to_string(rows.size()) + " " +
                         row.run.name + ": " + ms_text(row.round_ms.back()) + " per frame";
      if (round == 0) {
        // The settings decide the pixels; later rounds only time them again.
        std::vector<ssgi::CompareResult> against_ref, against_truth;
        for (std::size_t k = 0; k < report.frames.size(); ++k) {
          ssgi::FileCompareOptions compare;
          compare.depth_channel = depth;
          compare.channels = {"indirect"};
          against_ref.push_back(ssgi::compare_files(report.frames[k].output,
                                                    reference_report.frames[k].output, compare)
                                    .result);
          if (!truth.empty()) {
            compare.channels = {"indirect=" + truth};
            against_truth.push_back(
                ssgi::compare_files(report.frames[k].output, report.frames[k].input, compare)
                    .result);
          }
        }
        row.ref = scores_of(against_ref);
        row.truth = scores_of(against_truth);
        line += ", relRMSE " + number_text(row.ref.relrmse, "%.4f") + " against the reference";
        if (!truth.empty())
          line += ", " + number_text(row.truth.relrmse, "%.4f") + " against " + truth;
      }
      for (const ssgi::FrameReport& f : report.frames) {
        std::error_code ec;
        fs::remove(f.output, ec);
      }
      say(o, line);
    }
  }

  const bool against_truth = !truth.empty();
  std::vector<PlotPoint> points;
  for (const SweepRow& r : rows) {
    const std::optional<double> e = plotted_error(r, against_truth);
    points.push_back({r.run.name, r.ms_per_frame(), e && std::isfinite(*e) ? *e : 0.0});
  }
  const std::vector<bool> front = pareto_front(points);

  ssgi::write_text_atomically(o.run.output, csv_table(rows), "table");
  std::string written = o.run.output;
  if (!o.json_file.empty()) {
    ssgi::write_text_atomically(o.json_file, json_report(rows, front, context).dump(2) + "\n",
                                "JSON table");
    written += ", " + o.json_file;
  }
  if (!o.plot.empty()) {
    PlotText text;
    text.title = "ssgi sweep: " + fs::path(context.shot).filename().string();
    text.subtitle = "frames " + context.frames + ", " + std::to_string(context.width) + "x" +
                    std::to_string(context.height) + ", " + std::to_string(context.threads) +
                    " threads; error of the indirect light over surface pixels, mean of the "
                    "frames";
    text.x_title =
        "GI time per frame, ms (gi_ms: trace, bounces, denoise, temporal, composite; "
        "fastest of " +
        std::to_string(o.repeat) + (o.repeat == 1 ? " round)" : " rounds)");
    text.y_title = against_truth ? "relRMSE against " + truth + " (RMSE / mean)"
                                 : "relRMSE against ssgi reference, " +
                                       std::to_string(o.reference_spp) + " spp (RMSE / mean)";
    text.footnote = o.grid ? "grid runs sS-mM-bB: S slices, M samples per slice side, B bounces "
                             "(trace grid 480 across); presets: man ssgi-gi, PRESETS"
                           : "presets: man ssgi-gi, PRESETS";
    write_sweep_plot(points, text, o.plot);
    written += ", " + o.plot;
  }
  say(o, "wrote " + written);
  return kExitOk;
}

}  // namespace ssgi_cli
