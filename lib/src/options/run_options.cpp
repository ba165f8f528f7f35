#include "options/run_options.h"

#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <sstream>
#include <vector>

#include "log.h"
#include "memory.h"
#include "settings.h"
#include "simd.h"
#include "throw.h"

namespace ssgi_cli {
namespace {

double parse_double(const char* name, const char* text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (errno != 0 || end == text || *end != '\0' || !std::isfinite(v))
    ssgi::throw_usage(std::string("--") + name + ": '" + text + "' is not a number");
  return v;
}

long parse_long(const char* name, const char* text, long lo, long hi) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || v < lo || v > hi)
    ssgi::throw_usage(std::string("--") + name + ": '" + text + "' is not an integer in [" +
                      std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

std::array<float, 3> parse_color(const char* text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(parse_double("env-color", item.c_str()));
  if (values.size() == 1) values.assign(3, values[0]);
  if (values.size() != 3) ssgi::throw_usage("--env-color takes R,G,B or a single value");
  return {static_cast<float>(values[0]), static_cast<float>(values[1]),
          static_cast<float>(values[2])};
}

// --temporal none | ema[:ALPHA] | window[:K]
void parse_temporal(const char* text, ssgi::GiSettings* gi) {
  const std::string spec = text;
  const auto colon = spec.find(':');
  const std::string mode = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  const auto temporal = ssgi::enum_value(ssgi::kTemporalModeNames, mode);
  if (temporal == ssgi::TemporalMode::kNone && arg.empty()) {
    gi->temporal = *temporal;
  } else if (temporal == ssgi::TemporalMode::kEma) {
    gi->temporal = *temporal;
    if (!arg.empty()) gi->ema_alpha = static_cast<float>(parse_double("temporal", arg.c_str()));
  } else if (temporal == ssgi::TemporalMode::kWindow) {
    gi->temporal = *temporal;
    if (!arg.empty())
      gi->temporal_radius = static_cast<int>(parse_long("temporal", arg.c_str(), 1, 64));
  } else {
    ssgi::throw_usage("--temporal must be none, ema[:ALPHA] or window[:K]");
  }
}

// --multiframe off | on[:K]
void parse_multiframe(const char* text, ssgi::GiSettings* gi) {
  const std::string spec = text;
  if (spec == "off") {
    gi->multiframe = 0;
  } else if (spec == "on") {
    gi->multiframe = ssgi::kMultiframeWindow;
  } else if (spec.rfind("on:", 0) == 0) {
    gi->multiframe = static_cast<int>(parse_long("multiframe", spec.c_str() + 3, 1, 64));
  } else {
    ssgi::throw_usage("--multiframe must be off, on or on:K");
  }
}

// "--name" of an option id, for messages.
std::string written_name(int id) {
  for (const OptionSpec& spec : option_table())
    if (spec.id == id) return std::string("--") + spec.name;
  return "?";
}

}  // namespace

CommonOptions parse_common_options(Subcommand sub, int argc, char** argv, bool need_output) {
  CommonOptions o;
  o.run = subcommand_defaults(sub);
  o.reference_spp = subcommand_defaults(kReferenceCommand).gi.rays;
  ssgi::GiSettings& gi = o.run.gi;
  ssgi::InputOptions& in = o.run.input;
  for (int i = 0; i < argc; ++i) o.command_line += (i ? " " : "ssgi ") + std::string(argv[i]);
  // First every option as given (getopt_long, only this subcommand's table), then the preset,
  // then the others in order over it: the options given override what the preset sets.
  const std::vector<option> table = getopt_options(sub);
  const std::string short_options = getopt_short_options(sub);
  std::vector<std::pair<int, std::string>> given;
  optind = 0;  // getopt_long: restart (0 also resets GNU's internal state)
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, short_options.c_str(), table.data(), nullptr)) != -1) {
    if (c == ':') ssgi::throw_usage(std::string("option '") + argv[optind - 1] + "' needs a value");
    if (c == '?') {
      // optopt holds an unknown short option; an unknown long one is the last argument read.
      throw_unknown_option(sub, optopt > 0 && optopt < 128
                                    ? std::string("-") + static_cast<char>(optopt)
                                    : std::string(argv[optind - 1]));
    }
    given.emplace_back(c, optarg ? optarg : "");
    if (c == kPreset) o.preset = optarg;
  }
  if (sub & (kRunCommand | kInfoCommand | kPreviewCommand)) ssgi::apply_preset(o.preset, &gi);
  bool env_color_given = false;
  for (const auto& [id, value] : given) {
    const char* a = value.c_str();
    switch (id) {
      case 'o':
        o.run.output = a;
        break;
      case kFrames:
        // Empty would mean "every frame": a variable that expanded to nothing must not.
        if (*a == '\0') ssgi::throw_usage("--frames: empty frame list");
        in.frames = a;
        break;
      case kSkipMissing:
        in.skip_missing = true;
        break;
      case kLayout:
        in.layout = a;
        break;
      case kChannel:
        in.channel_overrides.push_back(a);
        break;
      case kDepthKind:
        in.depth_kind = a;
        break;
      case kNormals:
        in.normals = a;
        break;
      case kNormalSpace:
        in.normal_space = a;
        break;
      case kFov: {
        in.camera.hfov_deg = parse_double("fov", a);
        // Below 1e-6 degrees the focal length in pixels no longer fits a float.
        if (!(in.camera.hfov_deg >= 1e-6 && in.camera.hfov_deg < 180))
          ssgi::throw_usage("--fov must be at least 1e-6 and below 180 degrees");
        break;
      }
      case kCamera:
        in.camera.sidecar = a;
        break;
      case kContext:
        if (*a == '\0') ssgi::throw_usage("--context: empty pattern");
        in.context = a;
        break;
      case kGuide:
        if (*a == '\0') ssgi::throw_usage("--guide: empty pattern");
        in.guide = a;
        break;
      case kView:
      case kLatLongView: {
        if (*a == '\0')
          ssgi::throw_usage(std::string("option '") + written_name(id) + "' needs a file pattern");
        ssgi::ViewOptions v;
        v.pattern = a;
        v.projection = id == kLatLongView ? ssgi::Projection::kLatLong : ssgi::Projection::kPinhole;
        in.views.push_back(v);
        break;
      }
      case kRays:
        gi.rays = static_cast<int>(parse_long("rays", a, 1, 4096));
        break;
      case kTracer: {
        const auto tracer = ssgi::enum_value(ssgi::kTracerNames, a);
        // The Embree reference is `ssgi reference`, not a tracer of run.
        if (tracer && *tracer != ssgi::Tracer::kReference)
          gi.tracer = *tracer;
        else
          ssgi::throw_usage("--tracer must be slices or march");
        break;
      }
      case kSlices:
        gi.slices = static_cast<int>(parse_long("slices", a, 1, 256));
        break;
      case kTraceScale:
        gi.trace_scale =
            std::string(a) == "auto" ? 0 : static_cast<int>(parse_long("trace-scale", a, 1, 8));
        break;
      case kMaxSteps:
        gi.max_steps = static_cast<int>(parse_long("max-steps", a, 1, 1 << 20));
        break;
      case kMaxDistance:
        gi.max_distance = parse_double("max-distance", a);
        break;
      case kThickness:
        gi.thickness = parse_double("thickness", a);
        break;
      case kStartOffset:
        gi.start_offset = parse_double("start-offset", a);
        break;
      case kBounces:
        gi.bounces = static_cast<int>(parse_long("bounces", a, 1, 64));
        break;
      case kMiss: {
        if (const auto mode = ssgi::enum_value(ssgi::kMissModeNames, a))
          gi.miss = *mode;
        else
          ssgi::throw_usage("--miss must be auto, env, extend or frame");
        break;
      }
      case kEnv:
        gi.env_map = a;
        break;
      case kEnvUp: {
        const std::string up = a;
        if (up != "y" && up != "z") ssgi::throw_usage("--env-up must be y or z");
        gi.env_up = up[0];
        break;
      }
      case kEnvColor:
        gi.env_color = parse_color(a);
        env_color_given = true;
        break;
      case kGatherEmission:
        gi.gather_emission = 1;
        break;
      case kNoGatherEmission:
        gi.gather_emission = 0;
        break;
      case kDenoise: {
        if (const auto mode = ssgi::enum_value(ssgi::kDenoiseModeNames, a))
          gi.denoise = *mode;
        else
          ssgi::throw_usage("--denoise must be none or pyramid");
        break;
      }
      case kDenoiseRadius:
        gi.denoise_settings.radius = static_cast<int>(parse_long("denoise-radius", a, 0, 32));
        break;
      case kDenoiseSigmaSpatial:
        gi.denoise_settings.sigma_spatial =
            static_cast<float>(parse_double("denoise-sigma-spatial", a));
        break;
      case kDenoiseSigmaDepth:
        gi.denoise_settings.sigma_depth =
            static_cast<float>(parse_double("denoise-sigma-depth", a));
        break;
      case kDenoiseNormalPower:
        gi.denoise_settings.normal_power =
            static_cast<float>(parse_double("denoise-normal-power", a));
        break;
      case kDenoiseBlur:
        gi.denoise_settings.upsample_blur_radius =
            static_cast<int>(parse_long("denoise-blur", a, 0, 8));
        break;
      case kTemporal:
        parse_temporal(a, &gi);
        break;
      case kMultiframe:
        parse_multiframe(a, &gi);
        break;
      case kSpp:
        gi.rays = static_cast<int>(parse_long("spp", a, 1, 4096));
        break;
      case kJson:
        o.json = true;
        break;
      case kCheck:
        o.check = true;
        break;
      case kStats:
        if (*a == '\0') ssgi::throw_usage("--stats needs a file name");
        o.stats = a;
        break;
      case kPreset:
        break;  // applied before the other options (see above)
      case kSeed:
        gi.seed = static_cast<std::uint32_t>(parse_long("seed", a, 0, 4294967295L));
        break;
      case kSimd:
        if (*a == '\0') ssgi::throw_usage("--simd needs a target");
        o.simd = a;
        break;
      case kThreads:
        o.threads = static_cast<int>(parse_long("threads", a, 0, 4096));
        break;
      case kMaxMemory:
        o.run.memory_limit = {ssgi::parse_memory_size(a), "--max-memory"};
        break;
      case kFramesInFlight:
        o.run.frames_in_flight = static_cast<int>(parse_long("frames-in-flight", a, 1, 3));
        break;
      case kCompression:
        o.run.write.compression = parse_compression(a);
        break;
      case kDatatype: {
        const std::string t = a;
        if (t != "half" && t != "float") ssgi::throw_usage("--datatype must be half or float");
        o.run.write.half = t == "half";
        break;
      }
      case kNoPassthrough:
        o.run.write.passthrough = false;
        break;
      case kFailFast:
        o.run.fail_fast = true;
        break;
      case kSkipExisting:
        o.run.skip_existing = true;
        break;
      case kNoClobber:
        o.run.no_clobber = true;
        break;
      case kProgress: {
        const std::string mode = a;
        if (mode != "auto" && mode != "lines" && mode != "openjd" && mode != "deadline")
          ssgi::throw_usage("--progress must be auto, lines, openjd or deadline");
        o.progress = mode;
        break;
      }
      case kLayerPrefix:
        o.run.write.layer_prefix = parse_layer_prefix(a);
        break;
      case kPresets: {
        o.presets.clear();
        std::stringstream list(value);
        for (std::string name; std::getline(list, name, ',');) {
          const auto& known = ssgi::preset_names();
          if (std::find(known.begin(), known.end(), name) == known.end())
            ssgi::throw_usage("--presets: unknown preset '" + name + "' (" +
                              OIIO::Strutil::join(known, ", ") + ")");
          if (std::find(o.presets.begin(), o.presets.end(), name) == o.presets.end())
            o.presets.push_back(name);
        }
        break;
      }
      case kGrid:
        o.grid = true;
        break;
      case kTruth:
        if (*a == '\0') ssgi::throw_usage("--truth needs a layer name");
        o.truth = a;
        break;
      case kSweepJson:
        if (*a == '\0') ssgi::throw_usage("--json needs a file name");
        o.json_file = a;
        break;
      case kPlot:
        if (*a == '\0') ssgi::throw_usage("--plot needs a file name");
        o.plot = a;
        break;
      case kReferenceSpp:
        o.reference_spp = static_cast<int>(parse_long("reference-spp", a, 1, 4096));
        break;
      case kColorConfig:
      case kInputColorspace:
      case kOutputColorspace:
      case kEnvColorspace:
      case kWorkingSpace:
      case kDisplay:
      case kDisplayView: {
        ssgi::ColorSettings& c = gi.color;
        std::string* field = id == kColorConfig        ? &c.config
                             : id == kInputColorspace  ? &c.input
                             : id == kOutputColorspace ? &c.output
                             : id == kEnvColorspace    ? &c.env
                             : id == kWorkingSpace     ? &c.working
                             : id == kDisplay          ? &c.display
                                                       : &c.view;
        if (*a == '\0')
          ssgi::throw_usage(std::string("option '") + written_name(id) + "' needs a value");
        *field = a;
        break;
      }
      case kPreview:
        if (*a == '\0') ssgi::throw_usage("--preview needs a file name pattern");
        o.run.preview = a;
        break;
      case kReference:
        if (*a == '\0') ssgi::throw_usage("--reference needs a sequence");
        o.reference = a;
        break;
      case kRepeat:
        o.repeat = static_cast<int>(parse_long("repeat", a, 1, 100));
        break;
      case 'v':
        o.verbose = true;
        break;
      case 'q':
        o.quiet = true;
        break;
      case 'h':
        o.help = true;
        break;
      default:
        break;  // every id of the table is handled above
    }
  }
  if (o.verbose && o.quiet)
    ssgi::throw_usage("-v (--verbose) and -q (--quiet) contradict each other");
  if (o.help) return o;
  if (o.run.memory_limit.bytes == 0) o.run.memory_limit = ssgi::scheduler_memory_limit();
  // The kernels' target: --simd, else SSGI_SIMD (a bad value of either is a usage error here).
  const bool simd_given = !o.simd.empty();
  if (!simd_given && std::getenv("SSGI_SIMD") != nullptr) o.simd = std::getenv("SSGI_SIMD");
  if (!o.simd.empty()) {
    try {
      ssgi::set_simd_target(o.simd);
    } catch (const ssgi::Error& e) {
      ssgi::throw_usage(std::string(simd_given ? "--simd: " : "SSGI_SIMD: ") + e.what());
    }
  }
  // GNU getopt_long moves operands after the options, so `ssgi run IN -o OUT` works too.
  if (optind >= argc) ssgi::throw_usage("no input sequence given");
  if (argc - optind > 1)
    ssgi::throw_usage(std::string("unexpected argument '") + argv[optind + 1] + "'");
  in.pattern = argv[optind];
  if (need_output && o.run.output.empty())
    ssgi::throw_usage(sub == kSweepCommand     ? "no output given (-o FILE.csv)"
                      : sub == kPreviewCommand ? "no output given (-o FILE.png)"
                                               : "no output given (-o PATTERN)");
  if (sub == kSweepCommand && o.presets.empty() && !o.grid)
    ssgi::throw_usage("nothing to run: --presets is empty and --grid is not given");
  if (!gi.env_map.empty() && env_color_given)
    ssgi::throw_usage("--env and --env-color both give the environment: use one");
  return o;
}

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

void install_log_handler(bool verbose, bool quiet,
                         std::function<void(const std::string&)> print_line) {
  if (!print_line)
    print_line = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  ssgi::set_log_handler([verbose, quiet, print_line = std::move(print_line)](
                            ssgi::LogLevel level, const std::string& msg) {
    if (quiet) return;
    if (level == ssgi::LogLevel::kWarning)
      print_line("ssgi: warning: " + msg);
    else if (verbose)
      print_line("ssgi: " + msg);
  });
}

void warn_about_options(const CommonOptions& o) {
  if (o.run.write.compression.rfind("dwa", 0) == 0)
    ssgi::log_warning("DWA compression is lossy on channels named R, G, B (ssgi's outputs too)");
}

std::string parse_compression(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  static const std::set<std::string> kKnown = {"none",  "rle", "zips", "zip",  "piz",
                                               "pxr24", "b44", "b44a", "dwaa", "dwab"};
  if (!kKnown.count(name))
    ssgi::throw_usage(
        "unknown --compression '" + spec +
        "' (none, rle, zips, zip, piz, pxr24, b44, b44a, dwaa[:level], dwab[:level])");
  if (colon != std::string::npos) {
    if (name != "dwaa" && name != "dwab")
      ssgi::throw_usage("--compression '" + spec + "': only dwaa and dwab take a level");
    const std::string level = spec.substr(colon + 1);
    char* end = nullptr;
    const double v = std::strtod(level.c_str(), &end);
    if (level.empty() || *end != '\0' || !(v > 0) || v > 1e6)
      ssgi::throw_usage("--compression '" + spec + "': the level must be a positive number");
  }
  return spec;
}

std::string parse_layer_prefix(const std::string& prefix) {
  std::string p = prefix;
  if (!p.empty() && p.back() == '.') p.pop_back();
  bool ok = !p.empty() && p.front() != '.' && p.find("..") == std::string::npos;
  for (char c : p) ok = ok && c > ' ' && c < 127;
  if (!ok)
    ssgi::throw_usage("--layer-prefix '" + prefix +
                      "' is not a layer name (dot-separated names without spaces, e.g. ssgi)");
  return p + ".";
}

}  // namespace ssgi_cli
