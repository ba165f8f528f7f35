// The options of `ssgi run`, `ssgi info`, `ssgi reference`, `ssgi sweep` and `ssgi preview`, parsed
// with getopt_long from options/option_table.h.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "options/option_table.h"
#include "settings.h"
#include "ssgi/run.h"

namespace ssgi_cli {

struct CommonOptions {
  ssgi::RunOptions run;
  int threads = 0;
  bool verbose = false;
  bool quiet = false;
  bool help = false;
  std::string command_line;        // the whole invocation, for provenance
  bool json = false;               // --json (ssgi info)
  bool check = false;              // --check (ssgi info)
  std::string stats;               // --stats FILE.json (ssgi run)
  std::string preset = "default";  // --preset
  std::string progress = "auto";   // --progress auto|lines|openjd|deadline
  std::string simd;                // --simd TARGET; empty: SSGI_SIMD, else auto
  // ssgi sweep (its table goes to run.output, -o)
  std::vector<std::string> presets = ssgi::preset_names();  // --presets
  bool grid = false;                                        // --grid
  std::string truth;                                        // --truth LAYER
  std::string json_file;                                    // --json FILE
  std::string plot;                                         // --plot FILE.png
  int reference_spp = 256;                                  // --reference-spp
  int repeat = 1;                                           // --repeat
  // ssgi preview (its sheet goes to run.output, -o; --truth above)
  std::string reference;  // --reference PATTERN
};

// Parses argv (argv[0] is the subcommand) over subcommand_defaults(sub), with the options
// `sub` takes. `need_output` makes -o required. Throws ssgi::Error(kUsage) on a bad option or
// value.
CommonOptions parse_common_options(Subcommand sub, int argc, char** argv, bool need_output);

// "1-6", "1,4,7-9": frames (ascending) as compact ranges.
std::string frame_ranges(const std::vector<int>& frames);

// Sets up logging: warnings always (unless quiet), info lines when verbose, each line given to
// `print_line` (default: printed on stderr).
void install_log_handler(bool verbose, bool quiet,
                         std::function<void(const std::string&)> print_line = {});

// Warnings about option choices (lossy compression), once the log handler is installed.
void warn_about_options(const CommonOptions& options);

// Validates --compression (zip|zips|piz|rle|pxr24|b44|b44a|dwaa[:level]|dwab[:level]|none) and
// returns OIIO's spelling. Throws Error(kUsage) otherwise.
std::string parse_compression(const std::string& spec);

// Validates --layer-prefix (one or more dot-separated names, e.g. "ssgi" or "gi.v2", each of
// printable characters other than space) and returns it with its trailing '.'. Throws
// Error(kUsage) otherwise.
std::string parse_layer_prefix(const std::string& prefix);

}  // namespace ssgi_cli
