// ssgi compare: OIIO idiff's comparison, numbers, report and exit codes, over one pair of
// images or a sequence, with ssgi's own metrics (surface pixels, relRMSE, SSIM) on request.
#include <getopt.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "ssgi/compare.h"
#include "ssgi/error.h"
#include "ssgi/sequence.h"

namespace ssgi_cli {
namespace {

using Json = nlohmann::ordered_json;

enum CompareOptionId {
  kOptVerbose = 256,
  kOptQuiet,
  kOptAll,
  kOptFail,
  kOptFailRelative,
  kOptFailPercent,
  kOptHardFail,
  kOptAllowFailures,
  kOptWarn,
  kOptWarnRelative,
  kOptWarnPercent,
  kOptHardWarn,
  kOptPerceptual,
  kOptOutput,
  kOptOutputIfDifferent,
  kOptAbs,
  kOptScale,
  kOptDiff,
  kOptDiffScale,
  kOptChannels,
  kOptFrames,
  kOptMetric,
  kOptDepthChannel,
  kOptAllPixels,
  kOptJson,
  kOptHelp,
};

// One row per option: it makes both the getopt_long_only table and --help, so the two cannot
// drift. idiff's options come first, spelled as idiff spells them; getopt_long_only takes
// `-warn`, `--warn` and `-warn=X` alike.
enum class OptionGroup { kIdiff, kIdiffDifference, kSsgi };

struct CompareOptionRow {
  const char* name;
  int has_arg;
  int id;
  OptionGroup group;  // idiff's options are shown with one dash, ssgi's with two
  const char* arg;    // the argument's placeholder, nullptr for a flag
  const char* help;   // nullptr: an alias left out of the help
};

const CompareOptionRow kOptionRows[] = {
    // idiff: reporting
    {"v", no_argument, kOptVerbose, OptionGroup::kIdiff, nullptr,
     "print the numbers even when the images pass"},
    {"q", no_argument, kOptQuiet, OptionGroup::kIdiff, nullptr,
     "quiet: only FAILURE (on stderr) and errors"},
    {"a", no_argument, kOptAll, OptionGroup::kIdiff, nullptr,
     "compare every subimage (part), not only the first"},
    // idiff: thresholds
    {"fail", required_argument, kOptFail, OptionGroup::kIdiff, "X",
     "a pixel fails when a channel differs by more"},
    {"failrelative", required_argument, kOptFailRelative, OptionGroup::kIdiff, "R",
     "... and by more than R times the mean of |A| and |B|"},
    {"failpercent", required_argument, kOptFailPercent, OptionGroup::kIdiff, "P",
     "FAILURE when more than P% of the pixels fail"},
    {"hardfail", required_argument, kOptHardFail, OptionGroup::kIdiff, "H",
     "FAILURE when the max error exceeds H (checked only past -allowfailures)"},
    {"allowfailures", required_argument, kOptAllowFailures, OptionGroup::kIdiff, "N",
     "PASS whatever else when at most N pixels fail"},
    {"warn", required_argument, kOptWarn, OptionGroup::kIdiff, "X",
     "a pixel warns when a channel differs by more"},
    {"warnrelative", required_argument, kOptWarnRelative, OptionGroup::kIdiff, "R",
     "... and by more than R times the mean of |A| and |B|"},
    {"warnpercent", required_argument, kOptWarnPercent, OptionGroup::kIdiff, "P",
     "WARNING when more than P% of the pixels warn (and some pixel fails)"},
    {"hardwarn", required_argument, kOptHardWarn, OptionGroup::kIdiff, "H",
     "WARNING when the max error exceeds H (and some pixel fails)"},
    {"p", no_argument, kOptPerceptual, OptionGroup::kIdiff, nullptr,
     "idiff's perceptual test: refused (not built)"},
    // idiff: difference image
    {"o", required_argument, kOptOutput, OptionGroup::kIdiffDifference, "FILE",
     "write A - B (a pattern for sequences)"},
    {"od", no_argument, kOptOutputIfDifferent, OptionGroup::kIdiffDifference, nullptr,
     "... only when the images differ"},
    {"abs", no_argument, kOptAbs, OptionGroup::kIdiffDifference, nullptr, "... as |A - B|"},
    {"scale", required_argument, kOptScale, OptionGroup::kIdiffDifference, "S", "... times S"},
    {"diff", required_argument, kOptDiff, OptionGroup::kSsgi, "FILE", "the same as -o FILE -abs"},
    {"diff-scale", required_argument, kOptDiffScale, OptionGroup::kSsgi, "S",
     "the same as -scale S"},
    // ssgi
    {"channels", required_argument, kOptChannels, OptionGroup::kSsgi, "LIST",
     "compare these channels, paired by name: NAME or A_NAME=B_NAME, a channel or a layer with "
     "R,G,B (indirect=ViewLayer.DiffInd); default: every channel of each subimage, by index"},
    {"frames", required_argument, kOptFrames, OptionGroup::kSsgi, "LIST",
     "frames of a sequence (1-50, 1-50x2, 3,7,9); default: the pattern's range, else every "
     "frame on disk"},
    {"metric", required_argument, kOptMetric, OptionGroup::kSsgi, "LIST",
     "also ssgi's metrics per layer over surface pixels: rmse, relrmse, relmse, psnr, ssim or "
     "all (man ssgi-compare)"},
    {"depth-channel", required_argument, kOptDepthChannel, OptionGroup::kSsgi, "NAME",
     "for --metric: B's channel whose |value| >= 1e9, inf or NaN is background (default: Z or "
     "*depth.Z)"},
    {"all-pixels", no_argument, kOptAllPixels, OptionGroup::kSsgi, nullptr,
     "for --metric: no background, every pixel counts"},
    {"json", no_argument, kOptJson, OptionGroup::kSsgi, nullptr,
     "the results as JSON on stdout instead of the text"},
    {"help", no_argument, kOptHelp, OptionGroup::kSsgi, nullptr, "this text"},
    {"h", no_argument, kOptHelp, OptionGroup::kSsgi, nullptr, nullptr},
};

// The option as the help spells it: one dash for idiff's, two for ssgi's.
std::string spelled(const CompareOptionRow& row) {
  return (row.group == OptionGroup::kSsgi ? "--" : "-") + std::string(row.name);
}

std::string spelled(int id) {
  for (const CompareOptionRow& row : kOptionRows)
    if (row.id == id) return spelled(row);
  return "?";
}

std::vector<option> getopt_table() {
  std::vector<option> table;
  for (const CompareOptionRow& row : kOptionRows)
    table.push_back(option{row.name, row.has_arg, nullptr, row.id});
  table.push_back(option{nullptr, 0, nullptr, 0});
  return table;
}

std::string help_text() {
  std::string text = R"(usage: ssgi compare [options] A B

Compares image A with B as OIIO's idiff 2.4 does (single files or sequence patterns such as
out.####.exr, a frame at a time) and exits 0 (PASS), 1 (WARNING), 2 (FAILURE or a usage
error), 3 (data ssgi cannot compare: deep, a --channels name missing) or 4 (file error).
Every channel by index over the union of the data windows; options take one dash or two.

)";
  const char* headings[] = {"idiff's options:", "idiff's difference image:", "ssgi's options:"};
  std::optional<OptionGroup> group;
  for (const CompareOptionRow& row : kOptionRows) {
    if (!row.help) continue;
    if (group != row.group)
      text += std::string(group ? "\n" : "") + headings[static_cast<int>(row.group)] + "\n";
    group = row.group;
    std::string left = spelled(row);
    if (row.arg) left += std::string(" ") + row.arg;
    std::string line = "  " + left + std::string(left.size() < 20 ? 22 - left.size() : 2, ' ');
    // Wrap the help at 95 columns, under its own column.
    std::string help = row.help;
    constexpr std::size_t kWidth = 95 - 24;
    while (help.size() > kWidth) {
      std::size_t cut = help.rfind(' ', kWidth);
      if (cut == std::string::npos) cut = kWidth;
      line += help.substr(0, cut) + "\n" + std::string(24, ' ');
      help = help.substr(cut + 1);
    }
    text += line + help + "\n";
  }
  text +=
      "\nDefaults as idiff's: -fail 1e-06 -warn 1e-06, percents and relatives 0, hard limits "
      "inf.\nman ssgi-compare has the rules and the metric definitions.\n";
  return text;
}

struct Args {
  std::string a, b;
  std::string frames;
  bool verbose = false, quiet = false, json = false;
  std::vector<ssgi::Metric> metrics;  // empty: idiff's numbers only
  ssgi::IdiffOptions idiff;
  ssgi::FileCompareOptions file;  // ssgi's metrics
};

// A float in [lo, hi] (either may be infinite), as idiff reads its thresholds; the whole text
// must parse.
float parse_float(int id, const char* text, float lo, float hi) {
  char* end = nullptr;
  const float v = std::strtof(text, &end);
  if (end == text || *end != '\0' || std::isnan(v) || v < lo || v > hi) {
    char range[64];
    std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
    ssgi::throw_usage(spelled(id) + " '" + text + "': expected a number in " + range);
  }
  return v;
}

int parse_count(int id, const char* text) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < 0 || v > std::numeric_limits<int>::max())
    ssgi::throw_usage(spelled(id) + " '" + text + "': expected a pixel count (0 or more)");
  return static_cast<int>(v);
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
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const std::vector<option> table = getopt_table();
  Args args;
  ssgi::IdiffThresholds& t = args.idiff.thresholds;
  opterr = 0;  // we report errors ourselves, as usage errors
  optind = 0;  // GNU: full reinitialisation
  int opt;
  while ((opt = getopt_long_only(argc, argv, ":", table.data(), nullptr)) != -1) {
    switch (opt) {
      case kOptVerbose:
        args.verbose = true;
        break;
      case kOptQuiet:
        args.quiet = true;
        break;
      case kOptAll:
        args.idiff.all_subimages = true;
        break;
      case kOptFail:
        t.fail = parse_float(opt, optarg, 0.0f, kInf);
        break;
      case kOptFailRelative:
        t.fail_relative = parse_float(opt, optarg, 0.0f, kInf);
        break;
      case kOptFailPercent:
        t.fail_percent = parse_float(opt, optarg, 0.0f, 100.0f);
        break;
      case kOptHardFail:
        t.hard_fail = parse_float(opt, optarg, 0.0f, kInf);
        break;
      case kOptAllowFailures:
        t.allow_failures = parse_count(opt, optarg);
        break;
      case kOptWarn:
        t.warn = parse_float(opt, optarg, 0.0f, kInf);
        break;
      case kOptWarnRelative:
        t.warn_relative = parse_float(opt, optarg, 0.0f, kInf);
        break;
      case kOptWarnPercent:
        t.warn_percent = parse_float(opt, optarg, 0.0f, 100.0f);
        break;
      case kOptHardWarn:
        t.hard_warn = parse_float(opt, optarg, 0.0f, kInf);
        break;
      case kOptPerceptual:
        ssgi::throw_usage("-p (idiff's perceptual test) is not part of ssgi compare");
      case kOptDiff:
        args.idiff.diff_abs = true;
        [[fallthrough]];
      case kOptOutput:
        args.idiff.diff_path = optarg;
        if (args.idiff.diff_path.empty()) ssgi::throw_usage(spelled(opt) + " needs a file name");
        break;
      case kOptOutputIfDifferent:
        args.idiff.diff_only_if_different = true;
        break;
      case kOptAbs:
        args.idiff.diff_abs = true;
        break;
      case kOptScale:
      case kOptDiffScale:
        args.idiff.diff_scale = parse_float(opt, optarg, -3.4e38f, 3.4e38f);
        break;
      case kOptChannels:
        args.file.channels = args.idiff.channels = split_commas(optarg);
        break;
      case kOptFrames:
        args.frames = optarg;
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
      case kOptJson:
        args.json = true;
        break;
      case kOptHelp:
        std::fputs(help_text().c_str(), stdout);
        return std::nullopt;
      case ':':
        ssgi::throw_usage(std::string("option '") + argv[optind - 1] + "' needs a value");
      default:
        ssgi::throw_usage("unknown option '" + std::string(argv[optind - 1]) +
                          "' for ssgi compare");
    }
  }
  if (argc - optind != 2)
    ssgi::throw_usage("expected two images, A and B; got " + std::to_string(argc - optind));
  if (args.idiff.all_subimages && !args.idiff.channels.empty())
    ssgi::throw_usage(
        "-a compares subimages by index, --channels picks channels by name: not both");
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
  if (!args.idiff.diff_path.empty()) diff = ssgi::parse_sequence_pattern(args.idiff.diff_path);

  if (!a.has_frame_field && !b.has_frame_field) {
    if (!args.frames.empty()) ssgi::throw_usage("--frames needs a sequence pattern");
    if (diff && diff->has_frame_field)
      ssgi::throw_usage("-o has a frame field, but A and B are single files");
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
    ssgi::throw_usage("-o needs a frame field (e.g. diff.####.exr) for a sequence");

  std::vector<Job> jobs;
  for (int f : frames)
    jobs.push_back(Job{f, a.path_for(f), b.path_for(f), diff ? diff->path_for(f) : ""});
  return jobs;
}

// One frame's outcome: results, or the error that stopped it.
struct FrameOutcome {
  Job job;
  std::optional<ssgi::IdiffFileResult> idiff;
  std::optional<ssgi::FileCompareResult> metrics;  // with --metric
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

const char* idiff_word(ssgi::CompareStatus status) {
  switch (status) {
    case ssgi::CompareStatus::kOk:
      return "PASS";
    case ssgi::CompareStatus::kWarn:
      return "WARNING";
    case ssgi::CompareStatus::kFail:
      return "FAILURE";
  }
  return "?";
}

// A double as fmt's "{:g}" (printf's %g) prints it, NaN as "nan" whatever its sign.
std::string g_format(double v) {
  if (std::isnan(v)) return "nan";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// A float as fmt's "{}" prints it (as idiff does thresholds and pixel values): the shortest
// digits that read back as the same float, in fixed notation when the decimal exponent is in
// [-4, 16), else as 1.5e-05.
std::string shortest_format(float v) {
  if (std::isnan(v)) return std::signbit(v) ? "-nan" : "nan";
  if (std::isinf(v)) return v < 0 ? "-inf" : "inf";
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  const std::string sci(buf, end);  // -d.ddde+XX
  const std::size_t e_pos = sci.find('e');
  const bool negative = sci[0] == '-';
  std::string digits;
  for (std::size_t i = negative ? 1 : 0; i < e_pos; ++i)
    if (sci[i] != '.') digits += sci[i];
  const int exp = std::atoi(sci.c_str() + e_pos + 1);
  std::string out = negative ? "-" : "";
  const int n = static_cast<int>(digits.size());
  if (exp < -4 || exp >= 16) {
    out += digits.substr(0, 1);
    if (n > 1) out += "." + digits.substr(1);
    char e[16];
    std::snprintf(e, sizeof e, "e%c%02d", exp < 0 ? '-' : '+', std::abs(exp));
    return out + e;
  }
  if (exp < 0) return out + "0." + std::string(-exp - 1, '0') + digits;
  if (n <= exp + 1) return out + digits + std::string(exp + 1 - n, '0');
  return out + digits.substr(0, exp + 1) + "." + digits.substr(exp + 1);
}

std::string join_values(const std::vector<float>& values) {
  std::string out;
  for (std::size_t i = 0; i < values.size(); ++i)
    out += (i ? ", " : "") + shortest_format(values[i]);
  return out;
}

std::string metric_text(std::optional<double> v) {
  if (!v) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", *v);
  return buf;
}

// The text idiff prints, line for line, then ssgi's metrics (marked "ssgi") before the verdict.
class TextReport {
 public:
  explicit TextReport(const Args& args) : args_(args) {}

  // Before the files are read, as idiff does.
  void begin(const Job& job) {
    if (!args_.quiet) std::printf("Comparing \"%s\" and \"%s\"\n", job.a.c_str(), job.b.c_str());
    std::fflush(stdout);
  }

  void frame(const FrameOutcome& f) {
    if (f.error) {
      std::printf("  error: %s\n", error_text(*f.error).c_str());
      std::fflush(stdout);
      return;
    }
    const ssgi::IdiffFileResult& r = *f.idiff;
    for (const ssgi::IdiffSubimage& s : r.subimages) {
      if (!args_.verbose && (s.status == ssgi::CompareStatus::kOk || args_.quiet)) continue;
      if (args_.idiff.all_subimages) {
        if (r.a_subimages > 1) std::printf("Subimage %d : ", s.subimage);
        std::printf("%d x %d, %d channels\n", s.width, s.height, s.channels);
      }
      subimage(s);
    }
    if (args_.idiff.all_subimages && r.a_subimages != r.b_subimages && !args_.quiet)
      std::fprintf(stderr, "Images had differing numbers of subimages (%d vs %d)\n", r.a_subimages,
                   r.b_subimages);
    if (!args_.idiff.all_subimages && (r.a_subimages > 1 || r.b_subimages > 1) && !args_.quiet)
      std::printf("Only compared the first subimage (of %d and %d, respectively)\n", r.a_subimages,
                  r.b_subimages);
    if (f.metrics && !args_.quiet) {
      for (const ssgi::LayerStats& layer : f.metrics->result.layers)
        metrics_line(*f.metrics, layer);
      if (f.metrics->result.layers.size() > 1) metrics_line(*f.metrics, f.metrics->result.overall);
    }
    verdict(r.status);
    std::fflush(stdout);
  }

  // After a sequence: ssgi's metrics' mean and worst, the count per verdict, the verdict.
  void summary(const std::vector<FrameOutcome>& frames, const ssgi::SequenceSummary& s,
               const std::array<int, 3>& counts, std::optional<int> worst_frame,
               ssgi::CompareStatus status) {
    if (frames.size() < 2 || args_.quiet) {
      if (frames.size() >= 2) verdict(status);
      return;
    }
    if (!args_.metrics.empty()) {
      for (const char* label : {"mean", "worst"}) {
        auto row = [&](const ssgi::LayerSummary& layer) {
          std::printf("ssgi %s over the frames, %s:", label, layer.name.c_str());
          for (ssgi::Metric m : args_.metrics) {
            const ssgi::MetricSummary& ms = layer.metrics[static_cast<int>(m)];
            std::printf(" %s %s", ssgi::metric_name(m),
                        metric_text(label[0] == 'm' ? ms.mean : ms.worst).c_str());
          }
          std::printf("\n");
        };
        for (const ssgi::LayerSummary& layer : s.layers) row(layer);
        if (s.layers.size() > 1) row(s.overall);
      }
    }
    const std::size_t errors = static_cast<std::size_t>(std::count_if(
        frames.begin(), frames.end(), [](const FrameOutcome& f) { return f.error.has_value(); }));
    std::printf("%zu frames: %d PASS, %d WARNING, %d FAILURE, %zu error", frames.size(), counts[0],
                counts[1], counts[2], errors);
    if (worst_frame) std::printf("; worst frame %d", *worst_frame);
    std::printf("\n");
    verdict(status);
  }

 private:
  void subimage(const ssgi::IdiffSubimage& s) {
    const ssgi::IdiffStats& d = s.stats;
    std::printf("  Mean error = %s\n", g_format(d.mean_error).c_str());
    std::printf("  RMS error = %s\n", g_format(d.rms_error).c_str());
    std::printf("  Peak SNR = %s\n", g_format(d.psnr).c_str());
    std::printf("  Max error  = %s", g_format(d.max_error).c_str());
    if (d.max_error != 0.0) {
      const std::string channel = s.max_channel_name.empty()
                                      ? "channel " + std::to_string(d.max_channel)
                                      : s.max_channel_name;
      std::printf(" @ (%d, %d, %s)  values are %s vs %s", d.max_x, d.max_y, channel.c_str(),
                  join_values(s.a_values).c_str(), join_values(s.b_values).c_str());
    }
    std::printf("\n");
    const double npels = static_cast<double>(s.pixels);
    std::printf("  %zu pixels (%1.3g%%) over %s\n", d.warn_pixels, 100.0 * d.warn_pixels / npels,
                shortest_format(args_.idiff.thresholds.warn).c_str());
    std::printf("  %zu pixels (%1.3g%%) over %s\n", d.fail_pixels, 100.0 * d.fail_pixels / npels,
                shortest_format(args_.idiff.thresholds.fail).c_str());
  }

  void metrics_line(const ssgi::FileCompareResult& r, const ssgi::LayerStats& layer) {
    const std::string pixels = args_.file.all_pixels      ? "all pixels"
                               : !r.depth_channel.empty() ? "surface pixels by " + r.depth_channel
                                                          : "pixels where B is not 0";
    std::printf("  ssgi %s (%zu %s):", layer.name.c_str(), layer.foreground_pixels, pixels.c_str());
    for (ssgi::Metric m : args_.metrics)
      std::printf(" %s %s", ssgi::metric_name(m), metric_text(layer.metric(m)).c_str());
    std::printf("\n");
  }

  void verdict(ssgi::CompareStatus status) {
    if (!args_.quiet)
      std::printf("%s\n", idiff_word(status));
    else if (status == ssgi::CompareStatus::kFail)
      std::fprintf(stderr, "FAILURE\n");
  }

  const Args& args_;
};

// JSON has no infinity: undefined and infinite values are null.
Json json_number(std::optional<double> v) {
  return v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
}

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

Json subimage_json(const ssgi::IdiffSubimage& s) {
  const ssgi::IdiffStats& d = s.stats;
  Json j;
  j["subimage"] = s.subimage;
  j["width"] = s.width;
  j["height"] = s.height;
  j["channels"] = s.channels;
  j["pixels"] = s.pixels;
  j["mean_error"] = json_number(d.mean_error);
  j["rms_error"] = json_number(d.rms_error);
  j["psnr"] = json_number(d.psnr);
  j["max_error"] = json_number(d.max_error);
  j["max_error_at"] =
      d.max_error == 0.0 ? Json(nullptr)
                         : Json{{"x", d.max_x},
                                {"y", d.max_y},
                                {"channel", s.max_channel_name.empty() ? Json(d.max_channel)
                                                                       : Json(s.max_channel_name)}};
  j["warn_pixels"] = d.warn_pixels;
  j["fail_pixels"] = d.fail_pixels;
  j["status"] = ssgi::status_name(s.status);
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
  const ssgi::IdiffFileResult& r = *f.idiff;
  j["status"] = ssgi::status_name(r.status);
  j["a_subimages"] = r.a_subimages;
  j["b_subimages"] = r.b_subimages;
  j["subimages"] = Json::array();
  for (const ssgi::IdiffSubimage& s : r.subimages) j["subimages"].push_back(subimage_json(s));
  if (r.diff_written) j["diff"] = f.job.diff;
  if (f.metrics) {
    const ssgi::FileCompareResult& m = *f.metrics;
    j["depth_channel"] = m.depth_channel.empty() ? Json(nullptr) : Json(m.depth_channel);
    j["layers"] = Json::array();
    for (std::size_t i = 0; i < m.result.layers.size(); ++i)
      j["layers"].push_back(layer_json(args, m.result.layers[i], &m.layers[i]));
    j["overall"] = layer_json(args, m.result.overall, nullptr);
  }
  return j;
}

Json summary_json(const Args& args, const std::vector<FrameOutcome>& frames,
                  const std::vector<int>& metric_frame, const ssgi::SequenceSummary& s,
                  const std::array<int, 3>& counts, std::optional<int> worst_frame,
                  const char* status) {
  auto frame_of = [&](int index) {
    return index < 0 || !frames[0].job.frame ? Json(nullptr) : Json(metric_frame[index]);
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
  j["ok"] = counts[0];
  j["warn"] = counts[1];
  j["fail"] = counts[2];
  j["error"] = std::count_if(frames.begin(), frames.end(),
                             [](const FrameOutcome& f) { return f.error.has_value(); });
  j["status"] = status;
  j["worst_frame"] = worst_frame && frames[0].job.frame ? Json(*worst_frame) : Json(nullptr);
  if (!args.metrics.empty()) {
    j["layers"] = Json::object();
    for (const ssgi::LayerSummary& layer : s.layers) j["layers"][layer.name] = layer_summary(layer);
    j["overall"] = layer_summary(s.overall);
  }
  return j;
}

// The largest RMS error over a frame's subimages, which breaks ties between equal verdicts.
double worst_rms(const ssgi::IdiffFileResult& r) {
  double worst = -1.0;
  for (const ssgi::IdiffSubimage& s : r.subimages)
    worst = std::isnan(s.stats.rms_error) ? std::numeric_limits<double>::infinity()
                                          : std::max(worst, s.stats.rms_error);
  return worst;
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
  std::vector<ssgi::CompareResult> metrics;
  std::vector<int> metric_frame;  // frame number (0 for a single pair) of each entry of `metrics`
  std::array<int, 3> counts{};
  ssgi::CompareStatus status = ssgi::CompareStatus::kOk;
  std::optional<int> worst_frame;
  double worst_frame_rms = -1.0;
  for (const Job& job : jobs) {
    FrameOutcome outcome{job, std::nullopt, std::nullopt, std::nullopt};
    ssgi::IdiffOptions options = args.idiff;
    options.diff_path = job.diff;
    if (text) text->begin(job);
    try {
      outcome.idiff = ssgi::idiff_files(job.a, job.b, options);
      if (!args.metrics.empty()) outcome.metrics = ssgi::compare_files(job.a, job.b, args.file);
    } catch (const ssgi::Error& e) {
      // Usage errors are the same for every frame; a single pair reports its error as idiff does.
      if (e.kind() == ssgi::ErrorKind::kUsage || jobs.size() == 1) throw;
      outcome.idiff.reset();
      outcome.error = e;
    }
    if (text) text->frame(outcome);
    if (outcome.idiff) {
      const ssgi::CompareStatus s = outcome.idiff->status;
      ++counts[static_cast<int>(s)];
      const double rms = worst_rms(*outcome.idiff);
      if (!worst_frame || s > status || (s == status && rms > worst_frame_rms)) {
        status = std::max(status, s);
        worst_frame = job.frame.value_or(0);
        worst_frame_rms = rms;
      }
    }
    if (outcome.metrics) {
      metrics.push_back(outcome.metrics->result);
      metric_frame.push_back(job.frame.value_or(0));
    }
    frames.push_back(std::move(outcome));
  }
  const ssgi::Error* worst_error = nullptr;
  for (const FrameOutcome& f : frames) {
    if (f.error && (!worst_error || severity(*f.error) > severity(*worst_error)))
      worst_error = &*f.error;
  }

  const ssgi::SequenceSummary summary = ssgi::summarize_frames(metrics);
  if (text) {
    text->summary(frames, summary, counts, worst_frame, status);
  } else {
    Json out;
    out["a"] = args.a;
    out["b"] = args.b;
    const ssgi::IdiffThresholds& t = args.idiff.thresholds;
    out["thresholds"] = {{"fail", t.fail},
                         {"failrelative", t.fail_relative},
                         {"failpercent", t.fail_percent},
                         {"hardfail", json_number(t.hard_fail)},
                         {"allowfailures", t.allow_failures},
                         {"warn", t.warn},
                         {"warnrelative", t.warn_relative},
                         {"warnpercent", t.warn_percent},
                         {"hardwarn", json_number(t.hard_warn)}};
    out["metrics"] = Json::array();
    for (ssgi::Metric m : args.metrics) out["metrics"].push_back(ssgi::metric_name(m));
    out["relmse_epsilon"] = ssgi::kRelMseEpsilon;
    out["frames"] = Json::array();
    for (const FrameOutcome& f : frames) out["frames"].push_back(frame_json(args, f));
    out["summary"] = summary_json(args, frames, metric_frame, summary, counts, worst_frame,
                                  worst_error ? "error" : ssgi::status_name(status));
    std::printf("%s\n", out.dump(2).c_str());
  }
  std::fflush(stdout);
  // main() reports the error and maps its kind to 3 (data) or 4 (file): above any verdict.
  if (worst_error) throw *worst_error;
  return static_cast<int>(status);
}

}  // namespace ssgi_cli
