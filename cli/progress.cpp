#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "ssgi/error.h"
#include "ssgi/log.h"
#include "ssgi/temporary_files.h"
#include "ssgi/threads.h"

namespace ssgi_cli {
namespace {

int exit_code_for(ssgi::ErrorKind kind) {
  return kind == ssgi::ErrorKind::kInput   ? kExitInput
         : kind == ssgi::ErrorKind::kUsage ? kExitUsage
                                           : kExitIO;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// --stats: the frames' timings and the settings, as JSON, written whole or not at all.
void write_stats(const std::string& path, const CommonOptions& o, const ssgi::RunReport& report) {
  using Json = nlohmann::ordered_json;
  Json settings = Json::object();
  settings["preset"] = o.preset;
  for (const auto& [name, value] : ssgi::describe_settings(o.run.gi)) settings[name] = value;
  Json frames = Json::array();
  std::vector<double> read, gi, write;
  for (const ssgi::FrameReport& f : report.frames) {
    Json j = {{"frame", f.frame}, {"input", f.input}, {"output", f.output}, {"ok", f.ok}};
    if (f.ok) {
      j["read_ms"] = f.read_ms;
      j["gi_ms"] = f.gi_ms;
      j["write_ms"] = f.write_ms;
      read.push_back(f.read_ms);
      gi.push_back(f.gi_ms);
      write.push_back(f.write_ms);
    } else {
      j["error"] = f.error;
    }
    frames.push_back(std::move(j));
  }
  const Json out = {
      {"settings", settings},
      {"median", {{"read_ms", median(read)}, {"gi_ms", median(gi)}, {"write_ms", median(write)}}},
      {"frames", frames}};
  const std::string tmp = path + ".tmp";
  const ssgi::TemporaryFile registered(tmp);  // removed by a signal handler
  {
    std::ofstream file(tmp);
    file << out.dump(2) << "\n";
    if (!file.good()) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw ssgi::Error(ssgi::ErrorKind::kIO, path, "cannot write the statistics");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw ssgi::Error(ssgi::ErrorKind::kIO, path, "cannot write the statistics");
  }
}

}  // namespace

int run_with_progress(const CommonOptions& o) {
  install_log_handler(o.verbose, o.quiet);
  warn_about_options(o);
  const ssgi::ThreadLimit threads(o.threads);
  ssgi::log_info("threads: " + std::to_string(threads.budget().threads) + " (" +
                 threads.budget().source + ")");
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
  if (!o.stats.empty()) write_stats(o.stats, o, report);
  const int failed = report.failed();
  if (!o.quiet) {
    // The last line: how many frames were written, and which failed.
    const int attempted = static_cast<int>(report.frames.size()), written = attempted - failed;
    std::string line = "ssgi: " + std::to_string(written) + " of " + std::to_string(report.total) +
                       " frames written";
    if (failed > 0) {
      std::vector<int> which;
      for (const ssgi::FrameReport& f : report.frames)
        if (!f.ok) which.push_back(f.frame);
      line += ", " + std::to_string(failed) + " failed (" + frame_ranges(which) + ")";
    }
    if (attempted < report.total)
      line += ", " + std::to_string(report.total - attempted) + " not attempted (--fail-fast)";
    std::fprintf(stderr, "%s\n", line.c_str());
  }
  if (failed == 0) return kExitOk;
  // --fail-fast stopped at the frame that failed: its status says why.
  if (o.run.fail_fast) return exit_code_for(report.frames.back().error_kind);
  if (failed < static_cast<int>(report.frames.size())) return kExitSomeFramesFailed;
  return exit_code_for(report.frames.front().error_kind);
}

}  // namespace ssgi_cli
