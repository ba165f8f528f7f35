#include "run_options.h"

#include <getopt.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "ssgi/error.h"
#include "ssgi/io.h"
#include "ssgi/log.h"

namespace ssgi_cli {
namespace {

enum LongOnly : int {
  kFrames = 1000,
  kSkipMissing,
  kLayout,
  kChannel,
  kDepthKind,
  kFov,
  kCamera,
  kRays,
  kTracer,
  kSlices,
  kTraceScale,
  kMaxSteps,
  kMaxDistance,
  kThickness,
  kStartOffset,
  kBounces,
  kMiss,
  kEnv,
  kEnvUp,
  kEnvColor,
  kGatherEmission,
  kNoGatherEmission,
  kDenoise,
  kDenoiseRadius,
  kDenoiseSigmaSpatial,
  kDenoiseSigmaDepth,
  kDenoiseNormalPower,
  kDenoiseBlur,
  kTemporal,
  kSpp,
  kJson,
  kStats,
  kPreset,
  kSeed,
  kThreads,
  kCompression,
  kDatatype,
  kNoPassthrough,
  kLayerPrefix,
};

const option kOptions[] = {
    {"output", required_argument, nullptr, 'o'},
    {"frames", required_argument, nullptr, kFrames},
    {"skip-missing", no_argument, nullptr, kSkipMissing},
    {"layout", required_argument, nullptr, kLayout},
    {"channel", required_argument, nullptr, kChannel},
    {"depth-kind", required_argument, nullptr, kDepthKind},
    {"fov", required_argument, nullptr, kFov},
    {"camera", required_argument, nullptr, kCamera},
    {"rays", required_argument, nullptr, kRays},
    {"tracer", required_argument, nullptr, kTracer},
    {"slices", required_argument, nullptr, kSlices},
    {"trace-scale", required_argument, nullptr, kTraceScale},
    {"max-steps", required_argument, nullptr, kMaxSteps},
    {"max-distance", required_argument, nullptr, kMaxDistance},
    {"thickness", required_argument, nullptr, kThickness},
    {"start-offset", required_argument, nullptr, kStartOffset},
    {"bounces", required_argument, nullptr, kBounces},
    {"miss", required_argument, nullptr, kMiss},
    {"env", required_argument, nullptr, kEnv},
    {"env-up", required_argument, nullptr, kEnvUp},
    {"env-color", required_argument, nullptr, kEnvColor},
    {"gather-emission", no_argument, nullptr, kGatherEmission},
    {"no-gather-emission", no_argument, nullptr, kNoGatherEmission},
    {"denoise", required_argument, nullptr, kDenoise},
    {"denoise-radius", required_argument, nullptr, kDenoiseRadius},
    {"denoise-sigma-spatial", required_argument, nullptr, kDenoiseSigmaSpatial},
    {"denoise-sigma-depth", required_argument, nullptr, kDenoiseSigmaDepth},
    {"denoise-normal-power", required_argument, nullptr, kDenoiseNormalPower},
    {"denoise-blur", required_argument, nullptr, kDenoiseBlur},
    {"temporal", required_argument, nullptr, kTemporal},
    {"spp", required_argument, nullptr, kSpp},
    {"json", no_argument, nullptr, kJson},
    {"stats", required_argument, nullptr, kStats},
    {"preset", required_argument, nullptr, kPreset},
    {"seed", required_argument, nullptr, kSeed},
    {"threads", required_argument, nullptr, kThreads},
    {"compression", required_argument, nullptr, kCompression},
    {"datatype", required_argument, nullptr, kDatatype},
    {"no-passthrough", no_argument, nullptr, kNoPassthrough},
    {"layer-prefix", required_argument, nullptr, kLayerPrefix},
    {"verbose", no_argument, nullptr, 'v'},
    {"quiet", no_argument, nullptr, 'q'},
    {"help", no_argument, nullptr, 'h'},
    {nullptr, 0, nullptr, 0},
};

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
  if (mode == "none" && arg.empty()) {
    gi->temporal = ssgi::TemporalMode::kNone;
  } else if (mode == "ema") {
    gi->temporal = ssgi::TemporalMode::kEma;
    if (!arg.empty()) gi->ema_alpha = static_cast<float>(parse_double("temporal", arg.c_str()));
  } else if (mode == "window") {
    gi->temporal = ssgi::TemporalMode::kWindow;
    if (!arg.empty())
      gi->temporal_radius = static_cast<int>(parse_long("temporal", arg.c_str(), 1, 64));
  } else {
    ssgi::throw_usage("--temporal must be none, ema[:ALPHA] or window[:K]");
  }
}

}  // namespace

std::string unknown_option_name(char** argv) {
  // optopt holds an unknown short option; an unknown long one is the last argument read.
  return optopt > 0 && optopt < 128 ? std::string("-") + static_cast<char>(optopt)
                                    : std::string(argv[optind - 1]);
}

const char* common_options_help() {
  return "input:\n"
         "  --frames LIST         frames to write: 1-50, 1-50x2, 3,7,9, -5--1\n"
         "  --skip-missing        skip missing frames with a warning instead of failing\n"
         "  --layout NAME         channel layout preset (default: detected)\n"
         "  --channel ROLE=NAME   take ROLE (depth, normal, albedo, direct, emission, motion,\n"
         "                        position, beauty) from layer NAME or channels A,B,C\n"
         "  --depth-kind KIND     planar, radial, inverse or negative (default: the preset's)\n"
         "  --fov DEGREES         static camera with this horizontal field of view\n"
         "  --camera FILE.json    per-frame cameras from a sidecar file\n"
         "gi:\n"
         "  --preset P            draft, default or final: the tracing settings below (man\n"
         "                        ssgi, PRESETS); options given override it\n"
         "  --tracer T            slices (default) or march\n"
         "  --slices N            slices per traced pixel, 32 directions each (default 2)\n"
         "  --trace-scale N       trace one pixel in NxN: 1, 2, 4, 8 or auto (default: the\n"
         "                        preset's trace grid width, 480 across)\n"
         "  --max-steps N         samples per slice side or per march ray (default 28)\n"
         "  --rays N              march: rays per pixel and bounce (default 8)\n"
         "  --max-distance D      longest ray in scene units, 0 = unlimited (default 0)\n"
         "  --thickness T         a depth pixel is a slab from z to z*(1+T) (default 0.1)\n"
         "  --start-offset F      rays start F*depth off the surface (default 0.002)\n"
         "  --bounces N           diffuse bounces within the frame (default 8)\n"
         "  --miss MODE           what rays that miss bring: auto (default), frame, extend\n"
         "                        or env (man ssgi, MISSES)\n"
         "  --env FILE            lat-long environment map for rays that miss\n"
         "  --env-up y|z          the map's up axis in world space (default y)\n"
         "  --env-color R,G,B     constant radiance for rays that miss (default 0)\n"
         "  --gather-emission     rays pick up emission too (default: the preset's)\n"
         "  --no-gather-emission  rays pick up reflected direct light only\n"
         "  --denoise MODE        pyramid or none (default pyramid)\n"
         "  --denoise-radius N, --denoise-sigma-spatial S, --denoise-sigma-depth S,\n"
         "  --denoise-normal-power P, --denoise-blur N   denoise parameters (man ssgi)\n"
         "  --spp N               ssgi reference only: rays per pixel (default 256)\n"
         "  --json                ssgi info only: the report as JSON on stdout\n"
         "  --stats FILE.json     ssgi run only: per-frame read_ms, gi_ms, write_ms and the\n"
         "                        settings\n"
         "  --temporal MODE       window[:K] (default, K = 2), ema[:ALPHA] (default 0.1) or\n"
         "                        none\n"
         "  --seed N              noise seed (default 0)\n"
         "output:\n"
         "  -o, --output PATTERN  output sequence, e.g. out/shot.####.exr\n"
         "  --compression C       zip, zips, piz, rle, pxr24, b44, b44a, dwaa[:L], dwab[:L],\n"
         "                        none (default zip)\n"
         "  --datatype T          half or float for ssgi's channels (default float)\n"
         "  --no-passthrough      do not copy the input's channels\n"
         "  --layer-prefix P      write ssgi's channels under P.\n"
         "general:\n"
         "  --threads N           worker threads (default: all cores)\n"
         "  -v, --verbose         print the plan and per-frame timings\n"
         "  -q, --quiet           no progress, no warnings\n"
         "  -h, --help            this help\n";
}

CommonOptions parse_common_options(int argc, char** argv, bool need_output) {
  CommonOptions o;
  ssgi::GiSettings& gi = o.run.gi;
  ssgi::InputOptions& in = o.run.input;
  for (int i = 0; i < argc; ++i) o.command_line += (i ? " " : "ssgi ") + std::string(argv[i]);
  optind = 0;  // getopt_long: restart (0 also resets GNU's internal state)
  opterr = 0;
  bool env_color_given = false;
  // The preset first, whatever its place: the options given override what it sets.
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    if (arg == "--preset" && i + 1 < argc) o.preset = argv[i + 1];
    if (arg.rfind("--preset=", 0) == 0) o.preset = arg.substr(9);
  }
  ssgi::apply_preset(o.preset, &gi);
  int c;
  int option_index = -1;
  while ((c = getopt_long(argc, argv, ":o:vqh", kOptions, &option_index)) != -1) {
    const char* a = optarg;
    for (const option& known : kOptions)
      if (known.name != nullptr && known.val == c) o.given.insert(known.name);
    switch (c) {
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
      case kRays:
        gi.rays = static_cast<int>(parse_long("rays", a, 1, 4096));
        break;
      case kTracer: {
        const std::string t = a;
        if (t == "slices")
          gi.tracer = ssgi::Tracer::kSlices;
        else if (t == "march")
          gi.tracer = ssgi::Tracer::kScreenSpace;
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
        const std::string mode = a;
        if (mode == "frame")
          gi.miss = ssgi::MissMode::kFrame;
        else if (mode == "env")
          gi.miss = ssgi::MissMode::kEnvironment;
        else if (mode == "extend")
          gi.miss = ssgi::MissMode::kExtend;
        else if (mode == "auto")
          gi.miss = ssgi::MissMode::kAuto;
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
        const std::string mode = a;
        if (mode == "none")
          gi.denoise = ssgi::DenoiseMode::kNone;
        else if (mode == "pyramid")
          gi.denoise = ssgi::DenoiseMode::kPyramid;
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
      case kSpp:
        o.spp = static_cast<int>(parse_long("spp", a, 1, 4096));
        break;
      case kJson:
        o.json = true;
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
      case kThreads:
        o.threads = static_cast<int>(parse_long("threads", a, 0, 4096));
        break;
      case kCompression:
        o.run.write.compression = ssgi::parse_compression(a);
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
      case kLayerPrefix:
        o.run.write.layer_prefix = ssgi::parse_layer_prefix(a);
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
      case ':':
        ssgi::throw_usage(std::string("option '") + argv[optind - 1] + "' needs a value");
      default:
        ssgi::throw_usage("unknown option '" + unknown_option_name(argv) + "'");
    }
  }
  if (o.help) return o;
  // GNU getopt_long moves operands after the options, so `ssgi run IN -o OUT` works too.
  if (optind >= argc) ssgi::throw_usage("no input sequence given");
  if (argc - optind > 1)
    ssgi::throw_usage(std::string("unexpected argument '") + argv[optind + 1] + "'");
  in.pattern = argv[optind];
  if (need_output && o.run.output.empty()) ssgi::throw_usage("no output given (-o PATTERN)");
  if (!gi.env_map.empty() && env_color_given)
    ssgi::throw_usage("--env and --env-color both give the environment: use one");
  return o;
}

void install_log_handler(bool verbose, bool quiet) {
  ssgi::set_log_handler([verbose, quiet](ssgi::LogLevel level, const std::string& msg) {
    if (quiet) return;
    if (level == ssgi::LogLevel::kWarning)
      std::fprintf(stderr, "ssgi: warning: %s\n", msg.c_str());
    else if (verbose)
      std::fprintf(stderr, "ssgi: %s\n", msg.c_str());
  });
}

void warn_about_options(const CommonOptions& o) {
  if (o.run.write.compression.rfind("dwa", 0) == 0)
    ssgi::log_warning("DWA compression is lossy on channels named R, G, B (ssgi's outputs too)");
}

}  // namespace ssgi_cli
