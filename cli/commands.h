// The subcommands of the ssgi tool, one file each; main.cpp dispatches to them.
#pragma once

#include "ssgi/error.h"

namespace ssgi_cli {

// Exit codes, as documented in man/ssgi.1 (EXIT STATUS) and man/ssgi-compare.1.
enum ExitCode : int {
  kExitOk = 0,
  kExitSomeFramesFailed = 1,
  kExitUsage = 2,
  kExitInput = 3,
  kExitIO = 4,
  kExitInternal = 5,  // a bug: an invariant broke
};

// The exit code of an error of kind `kind`.
inline int exit_code_for(ssgi::ErrorKind kind) {
  switch (kind) {
    case ssgi::ErrorKind::kUsage:
      return kExitUsage;
    case ssgi::ErrorKind::kInput:
      return kExitInput;
    case ssgi::ErrorKind::kIO:
      return kExitIO;
    case ssgi::ErrorKind::kInternal:
      return kExitInternal;
  }
  return kExitInternal;
}

// Each takes the arguments after the subcommand name (argv[0] is the subcommand) and returns
// an exit code; ssgi::Error escaping from one is reported by main().
int run_run(int argc, char** argv);
int run_info(int argc, char** argv);
int run_compare(int argc, char** argv);
int run_reference(int argc, char** argv);
int run_sweep(int argc, char** argv);
int run_preview(int argc, char** argv);

}  // namespace ssgi_cli
