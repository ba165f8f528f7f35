// Options shared by `ssgi run` and `ssgi info` (the plan depends on them), parsed with
// getopt_long.
#pragma once

#include <set>
#include <string>

#include "ssgi/run.h"

namespace ssgi_cli {

struct CommonOptions {
  ssgi::RunOptions run;
  int threads = 0;
  bool verbose = false;
  bool quiet = false;
  bool help = false;
  std::string command_line;        // the whole invocation, for provenance
  int spp = 0;                     // --spp (ssgi reference), 0 when not given
  bool json = false;               // --json (ssgi info)
  std::string stats;               // --stats FILE.json (ssgi run)
  std::string preset = "default";  // --preset
  std::set<std::string> given;     // the long names of the options given, e.g. "denoise"
};

// Parses argv (argv[0] is the subcommand). `need_output` makes -o required. Throws
// ssgi::Error(kUsage) on a bad option or value.
CommonOptions parse_common_options(int argc, char** argv, bool need_output);

// After getopt_long returned '?': the option it did not know, as the user wrote it.
std::string unknown_option_name(char** argv);

// The option list for --help.
const char* common_options_help();

// Sets up logging to stderr: warnings always (unless quiet), info lines when verbose.
void install_log_handler(bool verbose, bool quiet);

// Warnings about option choices (lossy compression), once the log handler is installed.
void warn_about_options(const CommonOptions& options);

}  // namespace ssgi_cli
