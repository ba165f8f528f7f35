// The options of ssgi run, info, reference, sweep and preview in one table: name, argument, help,
// default and which subcommands take each. It drives getopt_long (each subcommand registers only
// its own options), the --help text (defaults read from the code's own defaults, not written out),
// the errors for unknown, ambiguous and misplaced options, and the man pages' check
// (tests/man_page_test.sh).
#pragma once

#include <getopt.h>

#include <string>
#include <vector>

#include "ssgi/run.h"

namespace ssgi_cli {

enum Subcommand : unsigned {
  kRunCommand = 1u,
  kInfoCommand = 2u,
  kReferenceCommand = 4u,
  kSweepCommand = 8u,
  kPreviewCommand = 16u,
};

// The subcommand's name as the user types it ("run").
const char* subcommand_name(Subcommand s);

// getopt_long's value for each long-only option (the short ones return their letter).
enum OptionId : int {
  kFrames = 1000,
  kSkipMissing,
  kLayout,
  kChannel,
  kDepthKind,
  kNormals,
  kNormalSpace,
  kFov,
  kCamera,
  kContext,
  kView,
  kLatLongView,
  kGuide,
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
  kMultiframe,
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
  kFailFast,
  kSkipExisting,
  kNoClobber,
  kProgress,
  kSimd,
  kCheck,
  kTruth,
  kPresets,
  kGrid,
  kSweepJson,
  kPlot,
  kReferenceSpp,
  kRepeat,
  kColorConfig,
  kInputColorspace,
  kOutputColorspace,
  kEnvColorspace,
  kWorkingSpace,
  kDisplay,
  kDisplayView,
  kPreview,
  kReference,
  kMaxMemory,
  kFramesInFlight,
};

enum class OptionGroup { kInput, kGi, kColor, kOutput, kGeneral };

struct OptionSpec {
  int id;            // what getopt_long returns: an OptionId or the short letter
  const char* name;  // the long name, without "--"
  char short_name;   // 0 when there is none
  const char* arg;   // the argument's placeholder in the help ("N"); nullptr for a flag
  OptionGroup group;
  unsigned subcommands;  // a mask of Subcommand
  const char* help;
  // The default as the help shows it, read from the subcommand's defaults; nullptr: none shown.
  std::string (*default_of)(const ssgi::RunOptions& defaults);
};

// Every option, in the help's order.
const std::vector<OptionSpec>& option_table();

// What a subcommand starts from before its options apply: the library's defaults with the
// default preset, and for reference its own (the Embree tracer, no denoiser, no temporal stage).
ssgi::RunOptions subcommand_defaults(Subcommand s);

// The getopt_long table of the options subcommand `s` takes, terminated by a zero entry.
std::vector<option> getopt_options(Subcommand s);

// getopt_long's short-option string for `s` (":o:vqh"-style, leading ':' for missing values).
std::string getopt_short_options(Subcommand s);

// The option list of `s` for --help, grouped, each with its default.
std::string options_help(Subcommand s);

// For an argument getopt_long did not accept (as written, "--lay" or "--spp=4"): throws
// Error(kUsage) saying whether it is ambiguous (and between which), an option of another
// subcommand, or unknown.
[[noreturn]] void throw_unknown_option(Subcommand s, const std::string& written);

}  // namespace ssgi_cli
