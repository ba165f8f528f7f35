// ssgi compare: error metrics and idiff-style thresholds between two images or sequences.
#include <getopt.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "run_options.h"
#include "ssgi/compare.h"
#include "ssgi/error.h"
#include "ssgi/sequence.h"

namespace ssgi_cli {
namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kHelp = R"(usage: ssgi compare [options] A B

Compares image A against the reference B (single EXR files or sequence patterns such as
out.####.exr) and exits 0 (ok), 1 (warning), 2 (failure or usage error), 3 (size or channel
mismatch) or 4 (file error), as OIIO's idiff does.

channels and pixels:
  --channels LIST       comma list of NAME or A_NAME=B_NAME; a name is a channel or a layer
                        with R,G,B (e.g. indirect=ViewLayer.DiffInd); default: every layer
                        with R,G,B in both files
  --depth-channel NAME  reference channel whose |value| >= 1e9, inf or NaN marks background;
                        default: Z or a *depth.Z channel of B, if any
  --all-pixels          no background: every pixel counts in the metrics
                        (without depth, a layer's background is where B is exactly 0)
  --frames LIST         frames of a sequence (1-50, 1-50x2, 3,7,9); default: the range in
                        the pattern, else every frame of A (or B) on disk

metrics:
  --metric LIST         rmse,relrmse,relmse,psnr,ssim or all (default all)

thresholds (per-pixel absolute difference, largest over the compared channels):
  --warn X              a pixel warns above X (default 1e-6)
  --warnpercent P       WARN when more than P% of pixels warn (default 0)
  --fail X              a pixel fails above X (default 1e-6)
  --failpercent P       FAIL when more than P% of pixels fail (default 0)
  --hardfail H          FAIL when any pixel differs by more than H (default inf)

output:
  --json                machine-readable results on stdout
  --diff OUT.exr        write |A - B| * S of the compared channels (a pattern for sequences)
  --diff-scale S        S above (default 1)
  -h, --help            this text

man ssgi has the metric definitions.
)";

enum OptionId {
  kOptChannels = 256,
  kOptMetric,
  kOptDepthChannel,
  kOptAllPixels,
  kOptFrames,
  kOptWarn,
  kOptWarnPercent,
  kOptFail,
  kOptFailPercent,
  kOptHardFail,
  kOptJson,
  kOptDiff,
  kOptDiffScale,
};

struct Args {
  std::string a, b;
  std::string frames;
  std::vector<ssgi::Metric> metrics = ssgi::parse_metric_list("all");
  bool json = false;
  ssgi::FileCompareOptions file;
};

// A number in [lo, hi] (either may be infinite); the whole text must parse.
double parse_number(const char* option, const char* text, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || std::isnan(v) || v < lo || v > hi) {
    char range[64];
    std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
    ssgi::throw_usage(std::string("--") + option + " '" + text + "': expected a number in " +
                      range);
  }
  return v;
}

std::vector<std::string> split_commas(const std::string& list) {
  std::vector<std::string> items;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = list.find(',', start);
    items.push_back(list.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return items;
}

// Returns nullopt after printing --help.
std::optional<Args> parse_args(int argc, char** argv) {
  static const option kOptions[] = {
      {"channels", required_argument, nullptr, kOptChannels},
      {"metric", required_argument, nullptr, kOptMetric},
      {"depth-channel", required_argument, nullptr, kOptDepthChannel},
      {"all-pixels", no_argument, nullptr, kOptAllPixels},
      {"frames", required_argument, nullptr, kOptFrames},
      {"warn", required_argument, nullptr, kOptWarn},
      {"warnpercent", required_argument, nullptr, kOptWarnPercent},
      {"fail", required_argument, nullptr, kOptFail},
      {"failpercent", required_argument, nullptr, kOptFailPercent},
      {"hardfail", required_argument, nullptr, kOptHardFail},
      {"json", no_argument, nullptr, kOptJson},
      {"diff", required_argument, nullptr, kOptDiff},
      {"diff-scale", required_argument, nullptr, kOptDiffScale},
      {"help", no_argument, nullptr, 'h'},
      {nullptr, 0, nullptr, 0},
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Args args;
  ssgi::Thresholds& t = args.file.compare.thresholds;
  opterr = 0;  // we report errors ourselves, as usage errors
  optind = 0;  // GNU: full reinitialisation
  int opt;
  while ((opt = getopt_long(argc, argv, ":h", kOptions, nullptr)) != -1) {
    switch (opt) {
      case kOptChannels:
        args.file.channels = split_commas(optarg);
        break;
      case kOptMetric:
        args.metrics = ssgi::parse_metric_list(optarg);
        break;
      case kOptDepthChannel:
        args.file.depth_channel = optarg;
        if (args.file.depth_channel.empty()) ssgi::throw_usage("--depth-channel needs a name");
        break;
      case kOptAllPixels:
        args.file.all_pixels = true;
        break;
      case kOptFrames:
        args.frames = optarg;
        break;
      case kOptWarn:
        t.warn = parse_number("warn", optarg, 0.0, kInf);
        break;
      case kOptWarnPercent:
        t.warn_percent = parse_number("warnpercent", optarg, 0.0, 100.0);
        break;
      case kOptFail:
        t.fail = parse_number("fail", optarg, 0.0, kInf);
        break;
      case kOptFailPercent:
        t.fail_percent = parse_number("failpercent", optarg, 0.0, 100.0);
        break;
      case kOptHardFail:
        t.hard_fail = parse_number("hardfail", optarg, 0.0, kInf);
        break;
      case kOptJson:
        args.json = true;
        break;
      case kOptDiff:
        args.file.diff_path = optarg;
        if (args.file.diff_path.empty()) ssgi::throw_usage("--diff needs a file name");
        break;
      case kOptDiffScale: {
        const double s = parse_number("diff-scale", optarg, 0.0, 3.4e38);
        if (s == 0.0) ssgi::throw_usage("--diff-scale must be above 0");
        args.file.diff_scale = static_cast<float>(s);
        break;
      }
      case 'h':
        std::fputs(kHelp, stdout);
        return std::nullopt;
      case ':':
        ssgi::throw_usage(std::string("option '") + argv[optind - 1] + "' needs a value");
      default:
        // optopt holds an unknown short option; an unknown long one is the last argument read.
        ssgi::throw_usage("unknown option '" +
                          (optopt > 0 && optopt < 128 ? std::string("-") + static_cast<char>(optopt)
                                                      : std::string(argv[optind - 1])) +
                          "' for ssgi compare");
    }
  }
  if (argc - optind != 2)
    ssgi::throw_usage("expected two images, A and the reference B; got " +
                      std::to_string(argc - optind));
  args.a = argv[optind];
  args.b = argv[optind + 1];
  args.file.compare.compute_ssim = std::find(args.metrics.begin(), args.metrics.end(),
                                             ssgi::Metric::kSsim) != args.metrics.end();
  return args;
}

// What to compare: one pair of files per frame, or a single pair.
struct Job {
  std::optional<int> frame;
  std::string a, b, diff;
};

std::vector<Job> plan_jobs(const Args& args) {
  std::vector<int> a_range, b_range;
  const ssgi::SequencePattern a = ssgi::parse_sequence_pattern(args.a, &a_range);
  const ssgi::SequencePattern b = ssgi::parse_sequence_pattern(args.b, &b_range);
  std::optional<ssgi::SequencePattern> diff;
  if (!args.file.diff_path.empty()) diff = ssgi::parse_sequence_pattern(args.file.diff_path);

  if (!a.has_frame_field && !b.has_frame_field) {
    if (!args.frames.empty()) ssgi::throw_usage("--frames needs a sequence pattern");
    if (diff && diff->has_frame_field)
      ssgi::throw_usage("--diff has a frame field, but A and B are single files");
    return {Job{std::nullopt, a.path_for(0), b.path_for(0), diff ? diff->path_for(0) : ""}};
  }
  // One side may be a single file, compared with every frame of the other.
  const ssgi::SequencePattern& sequence = a.has_frame_field ? a : b;
  std::vector<int> frames;
  if (!args.frames.empty())
    frames = ssgi::parse_frame_list(args.frames);
  else if (!a_range.empty())
    frames = a_range;
  else if (!b_range.empty())
    frames = b_range;
  else
    frames = ssgi::find_frames_on_disk(sequence);
  if (frames.empty())
    ssgi::throw_io(a.has_frame_field ? args.a : args.b, "no file on disk matches the pattern");
  if (diff && !diff->has_frame_field && frames.size() > 1)
    ssgi::throw_usage("--diff needs a frame field (e.g. diff.####.exr) for a sequence");

  std::vector<Job> jobs;
  for (int f : frames)
    jobs.push_back(Job{f, a.path_for(f), b.path_for(f), diff ? diff->path_for(f) : ""});
  return jobs;
}

// One frame's outcome: results, or the error that stopped it.
struct FrameOutcome {
  Job job;
  std::optional<ssgi::FileCompareResult> result;
  std::optional<ssgi::Error> error;
};

// Orders errors as their exit codes do: I/O (4) above input (3) above usage (2).
int severity(const ssgi::Error& e) {
  switch (e.kind()) {
    case ssgi::ErrorKind::kUsage:
      return 0;
    case ssgi::ErrorKind::kInput:
      return 1;
    case ssgi::ErrorKind::kIO:
    case ssgi::ErrorKind::kInternal:
      return 2;
  }
  return 2;
}

std::string error_text(const ssgi::Error& e) {
  return e.file().empty() ? e.what() : e.file() + ": " + e.what();
}

// JSON has no infinity: undefined and infinite values are null.
Json json_number(std::optional<double> v) {
  return v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
}

std::string text_number(std::optional<double> v) {
  if (!v) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", *v);
  return buf;
}

std::string frame_label(const Job& job) { return job.frame ? std::to_string(*job.frame) : "-"; }

double percent(std::size_t count, std::size_t total) {
  return total ? 100.0 * static_cast<double>(count) / static_cast<double>(total) : 0.0;
}

// The human-readable table, printed a frame at a time so that long runs show progress.
class TextReport {
 public:
  explicit TextReport(const Args& args) : args_(args) {
    std::printf("A: %s\nB: %s (reference)\n", args.a.c_str(), args.b.c_str());
  }

  void frame(const FrameOutcome& f) {
    if (f.error) {
      std::printf("%6s  error: %s\n", frame_label(f.job).c_str(), error_text(*f.error).c_str());
      std::fflush(stdout);
      return;
    }
    const ssgi::CompareResult& r = f.result->result;
    header(r);
    for (const ssgi::LayerStats& layer : r.layers) {
      row(frame_label(f.job), layer);
      std::printf("\n");
    }
    row(frame_label(f.job), r.overall);
    const ssgi::PixelDiffStats& d = r.pixels;
    std::printf("  %9.3g%% %9.3g%%  %s\n", percent(d.warn_pixels, d.pixels),
                percent(d.fail_pixels, d.pixels), ssgi::status_name(r.status));
    std::fflush(stdout);
  }

  void summary(const std::vector<FrameOutcome>& frames, const std::vector<int>& ok_frame,
               const ssgi::SequenceSummary& s) {
    const std::size_t errors = frames.size() - ok_frame.size();
    if (frames.size() > 1 && !ok_frame.empty()) {
      auto print_rows = [&](const char* label, auto&& value_of) {
        for (const ssgi::LayerSummary& layer : s.layers) summary_row(label, layer, value_of);
        summary_row(label, s.overall, value_of);
        std::printf("\n");
      };
      print_rows("mean", [](const ssgi::MetricSummary& m) { return m.mean; });
      print_rows("worst", [](const ssgi::MetricSummary& m) { return m.worst; });
      std::printf("%zu frames: %d ok, %d warn, %d fail, %zu error; worst frame %d (%s)\n",
                  frames.size(), s.status_counts[0], s.status_counts[1], s.status_counts[2], errors,
                  ok_frame[s.worst_index], ssgi::status_name(s.status));
    } else if (frames.size() == 1 && frames.front().result) {
      const ssgi::FileCompareResult& r = *frames.front().result;
      const ssgi::PixelDiffStats& d = r.result.pixels;
      std::printf("%zu pixels; %zu over warn %g, %zu over fail %g; max error %s", d.pixels,
                  d.warn_pixels, args_.file.compare.thresholds.warn, d.fail_pixels,
                  args_.file.compare.thresholds.fail, text_number(d.max_error).c_str());
      if (d.max_plane >= 0)
        std::printf(" at (%d, %d) %s", d.max_x, d.max_y, r.plane_names[d.max_plane].c_str());
      std::printf("\n%s\n", r.result.status == ssgi::CompareStatus::kOk     ? "PASS"
                            : r.result.status == ssgi::CompareStatus::kWarn ? "WARNING"
                                                                            : "FAILURE");
    }
  }

 private:
  void header(const ssgi::CompareResult& r) {
    if (printed_header_) return;
    printed_header_ = true;
    for (const ssgi::LayerStats& layer : r.layers)
      layer_width_ = std::max(layer_width_, static_cast<int>(layer.name.size()));
    std::printf("%6s  %-*s", "frame", layer_width_, "layer");
    for (ssgi::Metric m : args_.metrics) std::printf(" %11s", ssgi::metric_name(m));
    std::printf(" %11s  %10s %10s  %s\n", "max_error", ">warn", ">fail", "status");
  }

  void row(const std::string& frame, const ssgi::LayerStats& layer) {
    std::printf("%6s  %-*s", frame.c_str(), layer_width_, layer.name.c_str());
    for (ssgi::Metric m : args_.metrics) std::printf(" %11s", text_number(layer.metric(m)).c_str());
    std::printf(" %11s", text_number(layer.max_error).c_str());
  }

  template <typename ValueOf>
  void summary_row(const char* label, const ssgi::LayerSummary& layer, ValueOf&& value_of) {
    std::printf("%6s  %-*s", label, layer_width_, layer.name.c_str());
    for (ssgi::Metric m : args_.metrics)
      std::printf(" %11s", text_number(value_of(layer.metrics[static_cast<int>(m)])).c_str());
    std::printf("\n");
  }

  const Args& args_;
  bool printed_header_ = false;
  int layer_width_ = 8;
};

Json layer_json(const Args& args, const ssgi::LayerStats& layer,
                const ssgi::LayerChannels* channels) {
  Json j;
  j["name"] = layer.name;
  if (channels) {
    j["a_channels"] = channels->a;
    j["b_channels"] = channels->b;
  }
  for (ssgi::Metric m : args.metrics) j[ssgi::metric_name(m)] = json_number(layer.metric(m));
  j["max_error"] = json_number(layer.max_error);
  j["foreground_pixels"] = layer.foreground_pixels;
  j["samples"] = layer.samples;
  j["nonfinite_samples"] = layer.nonfinite_samples;
  j["reference_mean"] = layer.reference_mean;
  j["reference_peak"] =
      json_number(layer.samples ? std::optional(layer.reference_peak) : std::nullopt);
  return j;
}

Json frame_json(const Args& args, const FrameOutcome& f) {
  Json j;
  j["frame"] = f.job.frame ? Json(*f.job.frame) : Json(nullptr);
  j["a"] = f.job.a;
  j["b"] = f.job.b;
  if (f.error) {
    j["status"] = "error";
    j["error"] = error_text(*f.error);
    return j;
  }
  const ssgi::FileCompareResult& r = *f.result;
  const ssgi::PixelDiffStats& d = r.result.pixels;
  j["status"] = ssgi::status_name(r.result.status);
  j["pixels"] = d.pixels;
  j["warn_pixels"] = d.warn_pixels;
  j["fail_pixels"] = d.fail_pixels;
  j["max_error"] = json_number(d.max_error);
  j["max_error_at"] =
      d.max_plane < 0
          ? Json(nullptr)
          : Json{{"x", d.max_x}, {"y", d.max_y}, {"channel", r.plane_names[d.max_plane]}};
  j["depth_channel"] = r.depth_channel.empty() ? Json(nullptr) : Json(r.depth_channel);
  if (!f.job.diff.empty()) j["diff"] = f.job.diff;
  j["layers"] = Json::array();
  for (std::size_t i = 0; i < r.result.layers.size(); ++i)
    j["layers"].push_back(layer_json(args, r.result.layers[i], &r.layers[i]));
  j["overall"] = layer_json(args, r.result.overall, nullptr);
  return j;
}

Json summary_json(const Args& args, const std::vector<FrameOutcome>& frames,
                  const std::vector<int>& ok_frame, const ssgi::SequenceSummary& s,
                  const char* status) {
  auto frame_of = [&](int index) {
    return index < 0 || !frames[0].job.frame ? Json(nullptr) : Json(ok_frame[index]);
  };
  auto layer_summary = [&](const ssgi::LayerSummary& layer) {
    Json j;
    for (ssgi::Metric m : args.metrics) {
      const ssgi::MetricSummary& ms = layer.metrics[static_cast<int>(m)];
      j[ssgi::metric_name(m)] = {{"mean", json_number(ms.mean)},
                                 {"worst", json_number(ms.worst)},
                                 {"worst_frame", frame_of(ms.worst_index)}};
    }
    return j;
  };
  Json j;
  j["frames"] = frames.size();
  j["ok"] = s.status_counts[0];
  j["warn"] = s.status_counts[1];
  j["fail"] = s.status_counts[2];
  j["error"] = frames.size() - ok_frame.size();
  j["status"] = status;
  j["worst_frame"] = frame_of(s.worst_index);
  j["layers"] = Json::object();
  for (const ssgi::LayerSummary& layer : s.layers) j["layers"][layer.name] = layer_summary(layer);
  j["overall"] = layer_summary(s.overall);
  return j;
}

}  // namespace

int run_compare(int argc, char** argv) {
  const std::optional<Args> parsed = parse_args(argc, argv);
  if (!parsed) return kExitOk;
  const Args& args = *parsed;
  const std::vector<Job> jobs = plan_jobs(args);

  std::optional<TextReport> text;
  if (!args.json) text.emplace(args);
  std::vector<FrameOutcome> frames;
  std::vector<ssgi::CompareResult> ok;
  std::vector<int> ok_frame;  // frame number (0 for a single pair) of each entry of `ok`
  const ssgi::Error* worst_error = nullptr;
  for (const Job& job : jobs) {
    FrameOutcome outcome{job, std::nullopt, std::nullopt};
    ssgi::FileCompareOptions options = args.file;
    options.diff_path = job.diff;
    try {
      outcome.result = ssgi::compare_files(job.a, job.b, options);
    } catch (const ssgi::Error& e) {
      // Usage errors are the same for every frame: stop at once.
      if (e.kind() == ssgi::ErrorKind::kUsage) throw;
      outcome.error = e;
    }
    if (text) text->frame(outcome);
    if (outcome.result) {
      ok.push_back(outcome.result->result);
      ok_frame.push_back(job.frame.value_or(0));
    }
    frames.push_back(std::move(outcome));
  }
  for (const FrameOutcome& f : frames) {
    if (f.error && (!worst_error || severity(*f.error) > severity(*worst_error)))
      worst_error = &*f.error;
  }

  const ssgi::SequenceSummary summary = ssgi::summarize_frames(ok);
  const char* status = worst_error ? "error" : ssgi::status_name(summary.status);
  if (text) {
    text->summary(frames, ok_frame, summary);
  } else {
    Json out;
    out["a"] = args.a;
    out["b"] = args.b;
    out["metrics"] = Json::array();
    for (ssgi::Metric m : args.metrics) out["metrics"].push_back(ssgi::metric_name(m));
    const ssgi::Thresholds& t = args.file.compare.thresholds;
    out["thresholds"] = {{"warn", t.warn},
                         {"warnpercent", t.warn_percent},
                         {"fail", t.fail},
                         {"failpercent", t.fail_percent},
                         {"hardfail", json_number(t.hard_fail)}};
    out["relmse_epsilon"] = ssgi::kRelMseEpsilon;
    out["frames"] = Json::array();
    for (const FrameOutcome& f : frames) out["frames"].push_back(frame_json(args, f));
    out["summary"] = summary_json(args, frames, ok_frame, summary, status);
    std::printf("%s\n", out.dump(2).c_str());
  }
  std::fflush(stdout);
  // main() reports the error and maps its kind to 3 (mismatch) or 4 (file): above any status.
  if (worst_error) throw *worst_error;
  return static_cast<int>(summary.status);
}

}  // namespace ssgi_cli
