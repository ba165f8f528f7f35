#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "commands.h"
#include "io/temporary_files.h"
#include "log.h"
#include "settings.h"
#include "simd.h"
#include "ssgi/error.h"
#include "threads.h"

namespace ssgi_cli {
namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// "1:05", "1:02:03": a duration as a clock shows it.
std::string clock_text(double seconds) {
  const long s = std::max(0L, std::lround(seconds));
  char text[32];
  if (s >= 3600)
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  return text;
}

// What the run shows as it goes: on stderr a progress bar (a terminal) or a line per frame
// (anything else), nothing with -q; on stdout, with --progress openjd or deadline, the lines
// those schedulers parse. Log lines go through it, so that they never break the bar.
class ProgressDisplay {
 public:
  explicit ProgressDisplay(const CommonOptions& o)
      : bar_(!o.quiet && !o.verbose && o.progress == "auto" && isatty(STDERR_FILENO)),
        lines_(!o.quiet && !bar_),
        machine_(o.progress == "openjd" || o.progress == "deadline" ? o.progress : "") {}
  ~ProgressDisplay() { stop_ticker(); }
  ProgressDisplay(const ProgressDisplay&) = delete;
  ProgressDisplay& operator=(const ProgressDisplay&) = delete;

  void start(int total, int reused) {
    std::lock_guard<std::mutex> lock(mutex_);
    total_ = total;
    reused_left_ = reused;
    started_ = true;
    if (machine_ == "openjd") {
      std::printf("openjd_status: ssgi: %d frames to write%s\n", total,
                  reused ? (", " + std::to_string(reused) + " already written").c_str() : "");
      std::printf("openjd_progress: 0\n");
    } else if (machine_ == "deadline") {
      std::printf("Progress: 0%%\n");
    }
    std::fflush(stdout);
    if (bar_) {
      draw();
      // The clock keeps moving while a frame (the first: its whole window) is computed.
      ticker_ = std::thread([this] {
        std::unique_lock<std::mutex> lock(mutex_);
        while (!stopping_) {
          cv_.wait_for(lock, std::chrono::seconds(1));
          if (!stopping_) draw();
        }
      });
    }
  }

  void frame(const ssgi::FrameReport& f, int done, int total) {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = done;
    if (f.skipped) {
      --reused_left_;
    } else if (f.ok) {
      ++computed_;
    }
    if (!f.ok) {
      const std::string& file = f.error_file.empty() ? f.input : f.error_file;
      print_line("ssgi: error: " + file + ": " + f.error);
    } else if (lines_) {
      std::string line = "ssgi: frame " + std::to_string(f.frame) + " (" + std::to_string(done) +
                         "/" + std::to_string(total) + "): ";
      if (f.skipped) {
        line += f.output + " is there already, skipped";
      } else {
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, "%.2f s", f.seconds);
        line += f.input + " -> " + f.output + ", " + seconds;
        if (f.sanitized)
          line += ", " + std::to_string(f.sanitized) + " NaN or infinite input values read as 0";
      }
      print_line(line);
    }
    const double percent = 100.0 * done / std::max(1, total);
    if (machine_ == "openjd") {
      std::printf("openjd_progress: %.1f\n", percent);
      std::printf("openjd_status: frame %d %s (%d/%d)\n", f.frame,
                  f.skipped ? "already written"
                  : f.ok    ? "written"
                            : "failed",
                  done, total);
    } else if (machine_ == "deadline") {
      std::printf("Progress: %d%%\n", static_cast<int>(percent));
    }
    std::fflush(stdout);
    if (bar_) draw();
  }

  // A log line (a warning, or with -v an info line), above the bar.
  void message(const std::string& line) {
    std::lock_guard<std::mutex> lock(mutex_);
    print_line(line);
    if (bar_ && started_) draw();
  }

  // The run is over: the bar's last state stays on its line; openjd hears why it failed.
  void finish(const std::string& summary, bool failed) {
    stop_ticker();
    std::lock_guard<std::mutex> lock(mutex_);
    if (bar_ && started_) {
      draw();
      std::fprintf(stderr, "\n");
      bar_shown_ = false;
    }
    if (!summary.empty() && (lines_ || bar_)) std::fprintf(stderr, "%s\n", summary.c_str());
    std::fflush(stderr);
    if (failed && machine_ == "openjd") {
      std::printf("openjd_fail: %s\n", summary.c_str());
      std::fflush(stdout);
    }
  }

  // An error that stopped the whole run before or between frames.
  void fail(const std::string& message) {
    stop_ticker();
    std::lock_guard<std::mutex> lock(mutex_);
    if (bar_shown_) std::fprintf(stderr, "\r\033[K");
    bar_shown_ = false;
    if (machine_ == "openjd") {
      std::printf("openjd_fail: %s\n", message.c_str());
      std::fflush(stdout);
    }
  }

 private:
  void stop_ticker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    cv_.notify_all();
    if (ticker_.joinable()) ticker_.join();
  }

  void print_line(const std::string& line) {
    if (bar_shown_) std::fprintf(stderr, "\r\033[K");
    bar_shown_ = false;
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  }

  // [########------------]  3/10 frames  2.10 s/frame  0:07 elapsed, ETA 0:15
  void draw() {
    constexpr int kWidth = 24;
    const int filled = total_ > 0 ? kWidth * done_ / total_ : 0;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    std::string text = "\r\033[K[" + std::string(filled, '#') + std::string(kWidth - filled, '-') +
                       "] " + std::to_string(done_) + "/" + std::to_string(total_) + " frames";
    if (computed_ > 0) {
      // Wall time: frames are read, lit and written at once, so a frame's own seconds overstate
      // the rate.
      const double per_frame = elapsed / computed_;
      const int to_compute = total_ - done_ - reused_left_;
      char rate[64];
      std::snprintf(rate, sizeof rate, "  %.2f s/frame", per_frame);
      text += rate;
      text += "  " + clock_text(elapsed) + " elapsed, ETA " + clock_text(to_compute * per_frame);
    } else {
      text += "  " + clock_text(elapsed) + " elapsed";
    }
    std::fputs(text.c_str(), stderr);
    std::fflush(stderr);
    bar_shown_ = true;
  }

  const bool bar_, lines_;
  const std::string machine_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::thread ticker_;
  bool stopping_ = false, started_ = false, bar_shown_ = false;
  const Clock::time_point start_ = Clock::now();
  int total_ = 0, done_ = 0, reused_left_ = 0, computed_ = 0;
};

// --stats: the frames' timings, the settings and the run's outcome, as JSON, written whole or
// not at all.
void write_stats(const std::string& path, const CommonOptions& o, const ssgi::RunReport& report,
                 double seconds) {
  using Json = nlohmann::ordered_json;
  Json settings = Json::object();
  settings["preset"] = o.preset;
  for (const auto& [name, value] : ssgi::describe_settings(o.run.gi)) settings[name] = value;
  Json frames = Json::array(), failures = Json::array();
  std::vector<double> read, gi, write;
  double read_total = 0, gi_total = 0, write_total = 0;
  for (const ssgi::FrameReport& f : report.frames) {
    Json j = {{"frame", f.frame}, {"input", f.input}, {"output", f.output}, {"ok", f.ok}};
    if (f.skipped) {
      j["skipped"] = true;
    } else if (f.ok) {
      j["read_ms"] = f.read_ms;
      j["gi_ms"] = f.gi_ms;
      j["write_ms"] = f.write_ms;
      j["sanitized"] = f.sanitized;
      if (f.guide.used)
        j["guide"] = {{"known_share", f.guide.known_share},
                      {"residual_share", f.guide.residual_share},
                      {"detail_kept", f.guide.detail_kept}};
      read.push_back(f.read_ms);
      gi.push_back(f.gi_ms);
      write.push_back(f.write_ms);
      read_total += f.read_ms;
      gi_total += f.gi_ms;
      write_total += f.write_ms;
    } else {
      j["error"] = f.error;
      failures.push_back({{"frame", f.frame},
                          {"file", f.error_file.empty() ? f.input : f.error_file},
                          {"error", f.error}});
    }
    frames.push_back(std::move(j));
  }
  const int attempted = static_cast<int>(report.frames.size());
  const Json summary = {
      {"frames", report.total},
      {"written", attempted - report.failed() - report.skipped()},
      {"skipped", report.skipped()},
      {"failed", report.failed()},
      {"not_attempted", report.total - attempted},
      {"failures", failures},
      {"seconds", seconds},
      {"total", {{"read_ms", read_total}, {"gi_ms", gi_total}, {"write_ms", write_total}}}};
  const Json out = {
      {"settings", settings},
      {"summary", summary},
      {"median", {{"read_ms", median(read)}, {"gi_ms", median(gi)}, {"write_ms", median(write)}}},
      {"frames", frames}};
  ssgi::write_text_atomically(path, out.dump(2) + "\n", "statistics");
}

// The run's last line: how many frames were written, reused and failed, and which.
std::string summary_line(const ssgi::RunReport& report) {
  const int failed = report.failed(), skipped = report.skipped();
  const int attempted = static_cast<int>(report.frames.size());
  std::string line = "ssgi: " + std::to_string(attempted - failed - skipped) + " of " +
                     std::to_string(report.total) + " frames written";
  if (skipped > 0) line += ", " + std::to_string(skipped) + " skipped (already written)";
  if (failed > 0) {
    std::vector<int> which;
    for (const ssgi::FrameReport& f : report.frames)
      if (!f.ok) which.push_back(f.frame);
    line += ", " + std::to_string(failed) + " failed (" + frame_ranges(which) + ")";
  }
  if (attempted < report.total)
    line += ", " + std::to_string(report.total - attempted) + " not attempted (--fail-fast)";
  return line;
}

}  // namespace

int run_with_progress(const CommonOptions& o) {
  ProgressDisplay display(o);
  install_log_handler(o.verbose, o.quiet,
                      [&display](const std::string& line) { display.message(line); });
  warn_about_options(o);
  const ssgi::ThreadLimit threads(o.threads);
  ssgi::log_info("threads: " + std::to_string(threads.budget().threads) + " (" +
                 threads.budget().source + "), simd: " + ssgi::simd_target());
  ssgi::RunOptions run = o.run;
  run.write.provenance.emplace_back("ssgi:commandLine", o.command_line);

  const Clock::time_point start = Clock::now();
  ssgi::RunReport report;
  try {
    ssgi::RunCallbacks callbacks;
    callbacks.on_start = [&](int total, int reused) { display.start(total, reused); };
    callbacks.on_frame = [&](const ssgi::FrameReport& f, int done, int total) {
      display.frame(f, done, total);
    };
    report = ssgi::run_sequence(run, callbacks);
    if (!o.stats.empty())
      write_stats(o.stats, o, report, std::chrono::duration<double>(Clock::now() - start).count());
  } catch (const ssgi::Error& e) {
    display.fail(e.file().empty() ? e.what() : e.file() + ": " + e.what());
    install_log_handler(o.verbose, o.quiet);  // the display goes with this scope
    throw;
  }
  const int failed = report.failed();
  display.finish(summary_line(report), failed > 0);
  install_log_handler(o.verbose, o.quiet);
  if (failed == 0) return kExitOk;
  // --fail-fast stopped at the frame that failed: its status says why.
  if (o.run.fail_fast) return exit_code_for(report.frames.back().error_kind);
  if (failed < static_cast<int>(report.frames.size())) return kExitSomeFramesFailed;
  return exit_code_for(report.frames.front().error_kind);  // every frame failed
}

}  // namespace ssgi_cli
