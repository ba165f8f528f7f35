// ssgi compare's options: idiff's, spelled as idiff spells them, and ssgi's, in one table that
// makes both the getopt_long_only table and --help.
#include "options/compare_options.h"

#include <getopt.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "throw.h"

namespace ssgi_cli {
namespace {

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
     "also ssgi's metrics per layer over surface pixels: rmse, relrmse (rmse / B's mean), relmse, "
     "psnr, ssim or all (man ssgi-compare)"},
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

}  // namespace

// Returns nullopt after printing --help.
std::vector<ssgi::Metric> parse_metric_list(const std::string& list) {
  std::vector<ssgi::Metric> metrics;
  auto add = [&](ssgi::Metric m) {
    if (std::find(metrics.begin(), metrics.end(), m) == metrics.end()) metrics.push_back(m);
  };
  std::stringstream stream(list);
  std::string name;
  bool any = false;
  while (std::getline(stream, name, ',')) {
    any = true;
    bool known = false;
    for (int i = 0; i < ssgi::kMetricCount; ++i) {
      const ssgi::Metric m = static_cast<ssgi::Metric>(i);
      if (name == "all" || name == ssgi::metric_name(m)) {
        add(m);
        known = true;
      }
    }
    if (!known)
      ssgi::throw_usage("unknown metric '" + name + "' in '" + list +
                        "' (rmse, relrmse, relmse, psnr, ssim, all)");
  }
  if (!any) ssgi::throw_usage("empty metric list");
  return metrics;
}

std::optional<CompareArgs> parse_compare_args(int argc, char** argv) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const std::vector<option> table = getopt_table();
  CompareArgs args;
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
        args.metrics = parse_metric_list(optarg);
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

}  // namespace ssgi_cli
