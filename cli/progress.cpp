#include "progress.h"

#include <unistd.h>

#include <cstdio>
#include <string>

#include "commands.h"
#include "ssgi/error.h"
#include "ssgi/threads.h"

namespace ssgi_cli {
namespace {

int exit_code_for(ssgi::ErrorKind kind) {
  return kind == ssgi::ErrorKind::kInput   ? kExitInput
         : kind == ssgi::ErrorKind::kUsage ? kExitUsage
                                           : kExitIO;
}

}  // namespace

int run_with_progress(const CommonOptions& o) {
  if (o.json) ssgi::throw_usage("--json is for ssgi info");
  install_log_handler(o.verbose, o.quiet);
  warn_about_options(o);
  const ssgi::ThreadLimit threads(o.threads);
  ssgi::RunOptions run = o.run;
  run.write.provenance.emplace_back("ssgi:commandLine", o.command_line);

  const bool tty = isatty(STDERR_FILENO) && !o.verbose;
  const ssgi::RunReport report =
      ssgi::run_sequence(run, [&](const ssgi::FrameReport& f, int done, int total) {
        if (!f.ok) {
          if (tty) std::fprintf(stderr, "\r\033[K");
          const std::string& file = f.error_file.empty() ? f.input : f.error_file;
          std::fprintf(stderr, "ssgi: error: %s: %s\n", file.c_str(), f.error.c_str());
        }
        if (o.quiet) return;
        if (tty) {
          std::fprintf(stderr, "\r\033[K[%d/%d] frame %d  %.2f s", done, total, f.frame, f.seconds);
          if (done == total) std::fprintf(stderr, "\n");
        } else if (f.ok) {
          std::fprintf(stderr, "ssgi: frame %d (%d/%d): %s -> %s, %.2f s\n", f.frame, done, total,
                       f.input.c_str(), f.output.c_str(), f.seconds);
        }
        std::fflush(stderr);
      });
  const int failed = report.failed();
  if (failed == 0) return kExitOk;
  if (failed < static_cast<int>(report.frames.size())) return kExitSomeFramesFailed;
  return exit_code_for(report.frames.front().error_kind);
}

}  // namespace ssgi_cli
