// ssgi: screen-space diffuse global illumination for OpenEXR sequences.
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "commands.h"
#include "fast_malloc.h"
#include "io/temporary_files.h"
#include "ssgi/error.h"
#include "ssgi/version.h"

namespace {

struct Subcommand {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);
};

const Subcommand kSubcommands[] = {
    {"run", "add screen-space global illumination to a sequence", ssgi_cli::run_run},
    {"info", "print the layout, cameras and processing plan of a sequence", ssgi_cli::run_info},
    {"compare", "compare images or sequences with error metrics and thresholds",
     ssgi_cli::run_compare},
    {"reference", "trace the converged answer with Embree, to measure run against",
     ssgi_cli::run_reference},
    {"sweep", "time every preset on a shot against its error: a table and a plot",
     ssgi_cli::run_sweep},
    {"preview", "a labelled sheet of the passes of chosen frames: direct, indirect, gi, composite",
     ssgi_cli::run_preview},
};

void print_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: ssgi <subcommand> [options]\n"
               "       ssgi --help | --version\n\n"
               "subcommands:\n");
  for (const Subcommand& s : kSubcommands) std::fprintf(out, "  %-10s %s\n", s.name, s.summary);
  std::fprintf(out,
               "\n'ssgi <subcommand> --help' lists its options; man ssgi and man ssgi-<subcommand> "
               "have the rest.\n");
}

// SIGINT and SIGTERM: the file being written goes (every finished frame is already whole under
// its own name), one line says so, and the status is 128 + the signal's number (130, 143), as
// a shell reports a process the signal stopped. Only async-signal-safe calls.
extern "C" void stop_on_signal(int signal) {
  ssgi::remove_temporary_files();
  const char* message =
      signal == SIGINT ? "ssgi: stopped by SIGINT\n" : "ssgi: stopped by SIGTERM\n";
  const ssize_t ignored = ::write(STDERR_FILENO, message, std::strlen(message));
  (void)ignored;
  ::_exit(128 + signal);
}

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = stop_on_signal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM}) sigaction(signal, &action, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  install_signal_handlers();
  ssgi_cli::keep_no_freed_blocks();
  if (argc < 2) {
    print_usage(stderr);
    return ssgi_cli::kExitUsage;
  }
  const std::string first = argv[1];
  if (first == "--help" || first == "-h") {
    print_usage(stdout);
    return ssgi_cli::kExitOk;
  }
  if (first == "--version") {
    std::printf("ssgi %s\n", ssgi::version());
    return ssgi_cli::kExitOk;
  }
  for (const Subcommand& s : kSubcommands) {
    if (first != s.name) continue;
    try {
      return s.run(argc - 1, argv + 1);
    } catch (const ssgi::Error& e) {
      if (e.file().empty())
        std::fprintf(stderr, "ssgi: error: %s\n", e.what());
      else
        std::fprintf(stderr, "ssgi: error: %s: %s\n", e.file().c_str(), e.what());
      if (e.kind() == ssgi::ErrorKind::kUsage)
        std::fprintf(stderr, "Try 'ssgi %s --help'.\n", s.name);
      return ssgi_cli::exit_code_for(e.kind());
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "ssgi: error: out of memory\n");
      return ssgi_cli::kExitIO;
    } catch (const std::exception& e) {
      // Not an ssgi::Error: nothing meant it, a bug.
      std::fprintf(stderr, "ssgi: internal error: %s\n", e.what());
      return ssgi_cli::kExitInternal;
    }
  }
  std::fprintf(stderr, "ssgi: error: unknown subcommand '%s'\n", first.c_str());
  print_usage(stderr);
  return ssgi_cli::kExitUsage;
}
