#include "options/option_table.h"

#include <OpenImageIO/strutil.h>

#include <cstring>
#include <sstream>

#include "settings.h"
#include "throw.h"

namespace ssgi_cli {
namespace {

namespace Strutil = OIIO::Strutil;

// The options that say how frames are lit: run, info and reference, and preview (which lights
// the frames it shows).
constexpr unsigned kPlanning = kRunCommand | kInfoCommand | kReferenceCommand | kPreviewCommand;
// The options that say what the input is, and the general ones: sweep takes these too.
constexpr unsigned kReading = kPlanning | kSweepCommand;
// The tracing settings and presets: run, info and preview.
constexpr unsigned kTracing = kRunCommand | kInfoCommand | kPreviewCommand;
// The options of the EXR frames written: run and reference.
constexpr unsigned kWriting = kRunCommand | kInfoCommand | kReferenceCommand;

// A number as the help prints it: the shortest form that reads back as the same value.
std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

using ssgi::RunOptions;

// Each entry's default reads the subcommand's defaults (subcommand_defaults), so that the help
// cannot drift from the code.
const std::vector<OptionSpec> kTable = {
    // input
    {kFrames, "frames", 0, "LIST", OptionGroup::kInput, kReading,
     "frames to write: 1-50, 1-50x2, 3,7,9, -5--1 (default: the pattern's range, else every "
     "frame on disk)",
     nullptr},
    {kSkipMissing, "skip-missing", 0, nullptr, OptionGroup::kInput, kReading,
     "skip missing frames with a warning instead of failing", nullptr},
    {kLayout, "layout", 0, "NAME", OptionGroup::kInput, kReading,
     "channel layout preset (default: detected from the first frame)", nullptr},
    {kChannel, "channel", 0, "ROLE=NAME", OptionGroup::kInput, kReading,
     "take ROLE (depth, normal, albedo, direct, emission, motion, position, beauty) from layer "
     "NAME or channels A,B,C",
     nullptr},
    {kDepthKind, "depth-kind", 0, "KIND", OptionGroup::kInput, kReading,
     "planar, radial, inverse or negative (default: the layout's)", nullptr},
    {kNormals, "normals", 0, "SOURCE", OptionGroup::kInput, kReading,
     "auto (the file's normals, else from depth), pass or depth (from the depth buffer)", nullptr},
    {kNormalSpace, "normal-space", 0, "SPACE", OptionGroup::kInput, kReading,
     "the normal pass's space: world, camera (+z forward), camera-gl (-z forward) or auto (the "
     "one that agrees with the depth; default: the layout's)",
     nullptr},
    {kFov, "fov", 0, "DEGREES", OptionGroup::kInput, kReading,
     "a static camera with this horizontal field of view", nullptr},
    {kCamera, "camera", 0, "FILE.json", OptionGroup::kInput, kReading,
     "per-frame cameras from a sidecar file", nullptr},
    {kContext, "context", 0, "PATTERN", OptionGroup::kInput, kRunCommand | kInfoCommand,
     "a region render's whole frames: rays leaving the data window meet what they show", nullptr},
    {kView, "view", 0, "PATTERN", OptionGroup::kInput, kRunCommand | kInfoCommand | kSweepCommand,
     "an extra view of the scene (repeatable): a pinhole render with its own camera, e.g. a cube "
     "face, as a sequence (####) or a still; missed rays continue in it",
     nullptr},
    {kGuide, "guide", 0, "PATTERN", OptionGroup::kInput, kRunCommand | kInfoCommand | kSweepCommand,
     "a few-sample render of the shot with the renderer's diffuse indirect light (layout role "
     "indirect), at its resolution or a whole fraction of it: ssgi's light becomes its control "
     "variate",
     nullptr},
    {kLatLongView, "latlong-view", 0, "PATTERN", OptionGroup::kInput,
     kRunCommand | kInfoCommand | kSweepCommand,
     "the same for a lat-long (equirectangular) panorama, camera from worldToCamera", nullptr},
    // gi
    {kPreset, "preset", 0, "P", OptionGroup::kGi, kTracing,
     "draft, default or final: the tracing settings below (man ssgi-gi, PRESETS); options given "
     "override it",
     [](const RunOptions&) { return std::string("default"); }},
    {kTracer, "tracer", 0, "T", OptionGroup::kGi, kTracing, "slices or march",
     [](const RunOptions& d) {
       return std::string(ssgi::enum_name(ssgi::kTracerNames, d.gi.tracer));
     }},
    {kSlices, "slices", 0, "N", OptionGroup::kGi, kTracing,
     "slices per traced pixel, 32 directions each",
     [](const RunOptions& d) { return std::to_string(d.gi.slices); }},
    {kTraceScale, "trace-scale", 0, "N", OptionGroup::kGi, kTracing,
     "trace one pixel in NxN: 1, 2, 4, 8 or auto (the largest keeping the preset's trace grid "
     "width across)",
     [](const RunOptions& d) {
       return d.gi.trace_scale == 0 ? "auto, " + std::to_string(d.gi.trace_width) + " across"
                                    : std::to_string(d.gi.trace_scale);
     }},
    {kMaxSteps, "max-steps", 0, "N", OptionGroup::kGi, kTracing,
     "samples per slice side or per march ray",
     [](const RunOptions& d) { return std::to_string(d.gi.max_steps); }},
    {kRays, "rays", 0, "N", OptionGroup::kGi, kTracing, "--tracer march: rays per pixel and bounce",
     [](const RunOptions& d) { return std::to_string(d.gi.rays); }},
    {kSpp, "spp", 0, "N", OptionGroup::kGi, kReferenceCommand,
     "rays per pixel and bounce, 1 to 4096",
     [](const RunOptions& d) { return std::to_string(d.gi.rays); }},
    {kMaxDistance, "max-distance", 0, "D", OptionGroup::kGi, kPlanning,
     "longest ray in scene units, 0 = unlimited",
     [](const RunOptions& d) { return number(d.gi.max_distance); }},
    {kThickness, "thickness", 0, "T", OptionGroup::kGi, kPlanning,
     "a depth pixel is a slab from z to z*(1+T)",
     [](const RunOptions& d) { return number(d.gi.thickness); }},
    {kStartOffset, "start-offset", 0, "F", OptionGroup::kGi, kPlanning,
     "rays start F*depth off the surface, F in [0, 1]",
     [](const RunOptions& d) { return number(d.gi.start_offset); }},
    {kBounces, "bounces", 0, "N", OptionGroup::kGi, kPlanning,
     "diffuse bounces within the frame, 1 to 64",
     [](const RunOptions& d) { return std::to_string(d.gi.bounces); }},
    {kMiss, "miss", 0, "MODE", OptionGroup::kGi, kPlanning,
     "what rays that miss bring: auto, frame, extend or env (man ssgi-gi, MISSES)",
     [](const RunOptions& d) { return std::string(ssgi::miss_mode_name(d.gi.miss)); }},
    {kEnv, "env", 0, "FILE", OptionGroup::kGi, kPlanning,
     "lat-long environment map for rays that miss", nullptr},
    {kEnvUp, "env-up", 0, "y|z", OptionGroup::kGi, kPlanning, "the map's up axis in world space",
     [](const RunOptions& d) { return std::string(1, d.gi.env_up); }},
    {kEnvColor, "env-color", 0, "R,G,B", OptionGroup::kGi, kPlanning,
     "constant radiance for rays that miss",
     [](const RunOptions& d) {
       const auto& c = d.gi.env_color;
       return c[0] == c[1] && c[1] == c[2] ? number(c[0])
                                           : number(c[0]) + "," + number(c[1]) + "," + number(c[2]);
     }},
    {kGatherEmission, "gather-emission", 0, nullptr, OptionGroup::kGi, kPlanning,
     "rays pick up emission too (default: the layout's)", nullptr},
    {kNoGatherEmission, "no-gather-emission", 0, nullptr, OptionGroup::kGi, kPlanning,
     "rays pick up reflected direct light only", nullptr},
    {kDenoise, "denoise", 0, "MODE", OptionGroup::kGi, kPlanning, "pyramid or none",
     [](const RunOptions& d) {
       return std::string(ssgi::enum_name(ssgi::kDenoiseModeNames, d.gi.denoise));
     }},
    {kDenoiseRadius, "denoise-radius", 0, "N", OptionGroup::kGi, kPlanning,
     "the filter's radius at the pyramid's coarsest level, 0 to 32",
     [](const RunOptions& d) { return std::to_string(d.gi.denoise_settings.radius); }},
    {kDenoiseSigmaSpatial, "denoise-sigma-spatial", 0, "S", OptionGroup::kGi, kPlanning,
     "its spatial Gaussian, in pixels of that level",
     [](const RunOptions& d) { return number(d.gi.denoise_settings.sigma_spatial); }},
    {kDenoiseSigmaDepth, "denoise-sigma-depth", 0, "S", OptionGroup::kGi, kPlanning,
     "the relative depth difference weighing exp(-1/2)",
     [](const RunOptions& d) { return number(d.gi.denoise_settings.sigma_depth); }},
    {kDenoiseNormalPower, "denoise-normal-power", 0, "P", OptionGroup::kGi, kPlanning,
     "weight max(0, n.n')^P between normals",
     [](const RunOptions& d) { return number(d.gi.denoise_settings.normal_power); }},
    {kDenoiseBlur, "denoise-blur", 0, "N", OptionGroup::kGi, kPlanning,
     "radius of the edge-aware blur after each upsampling, 0 to 8",
     [](const RunOptions& d) {
       return std::to_string(d.gi.denoise_settings.upsample_blur_radius);
     }},
    {kTemporal, "temporal", 0, "MODE", OptionGroup::kGi, kPlanning,
     "window[:K] (frames +-K), ema[:ALPHA] or none",
     [](const RunOptions& d) { return ssgi::temporal_text(d.gi); }},
    {kMultiframe, "multiframe", 0, "MODE", OptionGroup::kGi, kPlanning,
     "on[:K] continues missed rays in the temporal window's frames (K each side at most), or off",
     [](const RunOptions& d) { return ssgi::multiframe_text(d.gi.multiframe); }},
    {kSeed, "seed", 0, "N", OptionGroup::kGi, kPlanning, "noise seed",
     [](const RunOptions& d) { return std::to_string(d.gi.seed); }},
    // colour
    {kColorConfig, "colorconfig", 0, "FILE", OptionGroup::kColor, kPlanning,
     "the OpenColorIO config (default: $OCIO, else none: no transform runs on EXR data)", nullptr},
    {kInputColorspace, "input-colorspace", 0, "NAME", OptionGroup::kColor, kPlanning,
     "the space of the light and albedo passes read (default: the working space; data passes "
     "are never transformed)",
     nullptr},
    {kOutputColorspace, "output-colorspace", 0, "NAME", OptionGroup::kColor, kWriting,
     "the space of ssgi's layers written (default: the working space; passed-through layers "
     "keep theirs)",
     nullptr},
    {kEnvColorspace, "env-colorspace", 0, "NAME", OptionGroup::kColor, kPlanning,
     "the environment map's space (default: sRGB for an 8- or 16-bit map, else the working "
     "space)",
     nullptr},
    {kWorkingSpace, "working-space", 0, "NAME", OptionGroup::kColor, kPlanning,
     "the space the GI arithmetic runs in (default: the config's scene_linear role)", nullptr},
    {kDisplay, "display", 0, "NAME", OptionGroup::kColor, kRunCommand | kPreviewCommand,
     "the preview's OCIO display (default: the config's default display; sRGB without a "
     "config)",
     nullptr},
    {kDisplayView, "display-view", 0, "NAME", OptionGroup::kColor, kRunCommand | kPreviewCommand,
     "the preview's view of that display (default: the display's default view)", nullptr},
    // output
    {kPreview, "preview", 0, "PATTERN", OptionGroup::kOutput, kRunCommand,
     "also write each frame's composite as a display-referred picture, e.g. prev.####.png "
     "(.png, .jpg)",
     nullptr},
    {'o', "output", 'o', "PATTERN", OptionGroup::kOutput, kWriting,
     "output sequence, e.g. out/shot.####.exr", nullptr},
    {kCompression, "compression", 0, "C", OptionGroup::kOutput, kWriting,
     "zip, zips, piz, rle, pxr24, b44, b44a, dwaa[:L], dwab[:L] or none",
     [](const RunOptions& d) { return d.write.compression; }},
    {kDatatype, "datatype", 0, "T", OptionGroup::kOutput, kWriting,
     "half or float for ssgi's channels",
     [](const RunOptions& d) { return std::string(d.write.half ? "half" : "float"); }},
    {kNoPassthrough, "no-passthrough", 0, nullptr, OptionGroup::kOutput, kWriting,
     "do not copy the input's channels", nullptr},
    {kLayerPrefix, "layer-prefix", 0, "P", OptionGroup::kOutput, kWriting,
     "write ssgi's channels under P. (e.g. ssgi.indirect.R)", nullptr},
    {kStats, "stats", 0, "FILE.json", OptionGroup::kOutput, kRunCommand | kReferenceCommand,
     "per-frame read_ms, gi_ms, write_ms, the settings and the run's summary", nullptr},
    {kJson, "json", 0, nullptr, OptionGroup::kOutput, kInfoCommand, "the report as JSON on stdout",
     nullptr},
    {kCheck, "check", 0, nullptr, OptionGroup::kGeneral, kInfoCommand,
     "also decode every frame as run would and load the environment map, computing nothing: "
     "what run would fail on fails here",
     nullptr},
    // sweep
    {kPresets, "presets", 0, "LIST", OptionGroup::kGi, kSweepCommand,
     "the presets to run, comma-separated",
     [](const RunOptions&) { return Strutil::join(ssgi::preset_names(), ","); }},
    {kGrid, "grid", 0, nullptr, OptionGroup::kGi, kSweepCommand,
     "also run 12 settings: slices 1, 2, 4 x max-steps 16, 28 x bounces 4, 8 (man ssgi-sweep)",
     nullptr},
    {kReferenceSpp, "reference-spp", 0, "N", OptionGroup::kGi, kSweepCommand,
     "rays per pixel and bounce of the Embree reference, 1 to 4096",
     [](const RunOptions&) {
       return std::to_string(subcommand_defaults(kReferenceCommand).gi.rays);
     }},
    {kTruth, "truth", 0, "LAYER", OptionGroup::kGi, kSweepCommand,
     "measure against this R,G,B layer of the input too (e.g. DiffInd: Cycles' path-traced "
     "indirect light)",
     nullptr},
    {kRepeat, "repeat", 0, "N", OptionGroup::kGi, kSweepCommand,
     "time each run N times, round by round; ms per frame is the fastest round's mean gi_ms",
     [](const RunOptions&) { return std::string("1"); }},
    {kTruth, "truth", 0, "LAYER", OptionGroup::kGi, kPreviewCommand,
     "also show the difference to this R,G,B layer of the input (e.g. ViewLayer.DiffInd)", nullptr},
    {kReference, "reference", 0, "PATTERN", OptionGroup::kGi, kPreviewCommand,
     "also show the difference to the indirect layer of this sequence (ssgi reference's)", nullptr},
    {'o', "output", 'o', "FILE.png", OptionGroup::kOutput, kPreviewCommand,
     "the sheet: one row per frame, one column per pass", nullptr},
    {'o', "output", 'o', "FILE.csv", OptionGroup::kOutput, kSweepCommand,
     "the table: one row per run", nullptr},
    {kSweepJson, "json", 0, "FILE", OptionGroup::kOutput, kSweepCommand,
     "the table as JSON too, with each run's settings and frame timings", nullptr},
    {kPlot, "plot", 0, "FILE.png", OptionGroup::kOutput, kSweepCommand,
     "error against time per frame, 1200x800 pixels", nullptr},
    // general
    {kFailFast, "fail-fast", 0, nullptr, OptionGroup::kGeneral, kRunCommand | kReferenceCommand,
     "stop at the first frame that fails (default: write the others, exit 1)", nullptr},
    {kSkipExisting, "skip-existing", 0, nullptr, OptionGroup::kGeneral,
     kRunCommand | kReferenceCommand,
     "keep outputs already there that read whole and were made by this ssgi version with these "
     "settings (their header says); make the others",
     nullptr},
    {kNoClobber, "no-clobber", 0, nullptr, OptionGroup::kGeneral, kRunCommand | kReferenceCommand,
     "refuse to run, before computing anything, if an output would be overwritten", nullptr},
    {kProgress, "progress", 0, "MODE", OptionGroup::kGeneral, kRunCommand | kReferenceCommand,
     "auto (a bar on a terminal, else a line per frame), lines, openjd (openjd_progress: lines "
     "on stdout) or deadline (Progress: N% on stdout)",
     [](const RunOptions&) { return std::string("auto"); }},
    {kThreads, "threads", 0, "N", OptionGroup::kGeneral, kReading,
     "worker threads (default: the scheduler's allocation, else the CPUs allowed)", nullptr},
    {kMaxMemory, "max-memory", 0, "SIZE", OptionGroup::kGeneral, kRunCommand | kReferenceCommand,
     "the most memory the run may take: the fastest plan whose estimated peak fits SIZE, and a "
     "refusal before computing anything when none does (500M, 2G or bytes; default: the "
     "scheduler's limit, Slurm's allocation or the cgroup's, else none: the least memory; -v "
     "says which)",
     nullptr},
    {kMaxMemory, "max-memory", 0, "SIZE", OptionGroup::kGeneral, kInfoCommand,
     "plan the run under SIZE: the memory section says how it fits (fewer frames in flight, "
     "frames read twice) or that run would refuse it (500M, 2G or bytes; default: the "
     "scheduler's limit, Slurm's allocation or the cgroup's)",
     nullptr},
    {kFramesInFlight, "frames-in-flight", 0, "N", OptionGroup::kGeneral,
     kRunCommand | kInfoCommand | kReferenceCommand,
     "frames read, lit and written at once: 1 (one after the other, the least memory) to 3, "
     "the window's frames kept rather than read twice; fewer when --max-memory needs it "
     "(default: as many as the limit fits, up to 2; without a limit 1, the frames read twice)",
     nullptr},
    {kSimd, "simd", 0, "TARGET", OptionGroup::kGeneral, kReading,
     "the kernels' instruction set: auto, a target this CPU has (avx2, sse4, ...; ssgi info "
     "lists them) or scalar; every one gives the same bits (default: $SSGI_SIMD, else auto)",
     nullptr},
    {'v', "verbose", 'v', nullptr, OptionGroup::kGeneral, kReading,
     "print the plan and per-frame timings", nullptr},
    {'q', "quiet", 'q', nullptr, OptionGroup::kGeneral, kReading, "no progress, no warnings",
     nullptr},
    {'h', "help", 'h', nullptr, OptionGroup::kGeneral, kReading, "this help", nullptr},
};

const char* group_name(OptionGroup g) {
  switch (g) {
    case OptionGroup::kInput:
      return "input";
    case OptionGroup::kGi:
      return "gi";
    case OptionGroup::kColor:
      return "colour";
    case OptionGroup::kOutput:
      return "output";
    case OptionGroup::kGeneral:
      return "general";
  }
  return "";
}

// "--name", "--name=" prefix of a written argument, without the value.
std::string written_name(const std::string& written) {
  std::string name = written;
  while (!name.empty() && name.front() == '-') name.erase(name.begin());
  const auto eq = name.find('=');
  return eq == std::string::npos ? name : name.substr(0, eq);
}

// The subcommands of `mask`, as "ssgi run or ssgi info".
std::string subcommands_text(unsigned mask) {
  std::vector<std::string> names;
  for (Subcommand s :
       {kRunCommand, kInfoCommand, kReferenceCommand, kSweepCommand, kPreviewCommand})
    if (mask & s) names.push_back(std::string("ssgi ") + subcommand_name(s));
  return Strutil::join(names, " or ");
}

}  // namespace

const char* subcommand_name(Subcommand s) {
  switch (s) {
    case kRunCommand:
      return "run";
    case kInfoCommand:
      return "info";
    case kReferenceCommand:
      return "reference";
    case kSweepCommand:
      return "sweep";
    case kPreviewCommand:
      return "preview";
  }
  return "";
}

const std::vector<OptionSpec>& option_table() { return kTable; }

ssgi::RunOptions subcommand_defaults(Subcommand s) {
  ssgi::RunOptions d;
  ssgi::apply_preset("default", &d.gi);
  if (s == kReferenceCommand) {
    // The reference is each frame's converged answer: a denoiser or a temporal filter would
    // only add its own bias.
    d.gi.tracer = ssgi::Tracer::kReference;
    d.gi.rays = 256;
    d.gi.denoise = ssgi::DenoiseMode::kNone;
    d.gi.temporal = ssgi::TemporalMode::kNone;
  }
  // The sweep runs one frame at a time: a frame's gi_ms is then its GI's own time, not shared
  // with the decoding and encoding of the frames around it.
  if (s == kSweepCommand) d.frames_in_flight = 1;
  return d;
}

std::vector<option> getopt_options(Subcommand s) {
  std::vector<option> out;
  for (const OptionSpec& o : kTable)
    if (o.subcommands & s)
      out.push_back({o.name, o.arg ? required_argument : no_argument, nullptr, o.id});
  out.push_back({nullptr, 0, nullptr, 0});
  return out;
}

std::string getopt_short_options(Subcommand s) {
  std::string out = ":";
  for (const OptionSpec& o : kTable) {
    if (!(o.subcommands & s) || o.short_name == 0) continue;
    out += o.short_name;
    if (o.arg) out += ':';
  }
  return out;
}

std::string options_help(Subcommand s) {
  const ssgi::RunOptions defaults = subcommand_defaults(s);
  constexpr int kColumn = 24, kWidth = 79;
  std::string out;
  for (OptionGroup g : {OptionGroup::kInput, OptionGroup::kGi, OptionGroup::kColor,
                        OptionGroup::kOutput, OptionGroup::kGeneral}) {
    std::string lines;
    for (const OptionSpec& o : kTable) {
      if (o.group != g || !(o.subcommands & s)) continue;
      std::string left = "  ";
      if (o.short_name) left += std::string("-") + o.short_name + ", ";
      left += std::string("--") + o.name;
      if (o.arg) left += std::string(" ") + o.arg;
      std::string help = o.help;
      if (o.default_of) help += " (default: " + o.default_of(defaults) + ")";
      std::string line = left.size() + 1 < kColumn ? left + std::string(kColumn - left.size(), ' ')
                                                   : left + "\n" + std::string(kColumn, ' ');
      // Continuation lines start in the help column.
      line += Strutil::wordwrap(help, kWidth, kColumn);
      lines += line + "\n";
    }
    if (!lines.empty()) out += std::string(group_name(g)) + ":\n" + lines;
  }
  return out;
}

void throw_unknown_option(Subcommand s, const std::string& written) {
  const std::string command = std::string("ssgi ") + subcommand_name(s);
  const bool long_form = written.rfind("--", 0) == 0;
  const std::string name = written_name(written);
  if (long_form && !name.empty()) {
    std::vector<std::string> matches;
    for (const OptionSpec& o : kTable)
      if ((o.subcommands & s) && std::strncmp(o.name, name.c_str(), name.size()) == 0)
        matches.push_back(std::string("--") + o.name);
    if (matches.size() > 1)
      ssgi::throw_usage("ambiguous option '" + written + "' for " + command + ": " +
                        Strutil::join(matches, ", "));
    for (const OptionSpec& o : kTable)
      if (name == o.name && !(o.subcommands & s))
        ssgi::throw_usage("'--" + name + "' is not an option of " + command + " (it is of " +
                          subcommands_text(o.subcommands) + ")");
  }
  ssgi::throw_usage("unknown option '" + written + "' for " + command);
}

}  // namespace ssgi_cli
