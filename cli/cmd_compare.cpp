// ssgi compare: OIIO idiff's comparison, numbers, report and exit codes, over one pair of
// images or a sequence, with ssgi's own metrics (surface pixels, relRMSE, SSIM) on request.
// The options are lib/src/options/compare_options.cpp's, the report compare_report.cpp's.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "compare/compare.h"
#include "compare/compare_files.h"
#include "compare_command.h"
#include "io/sequence.h"
#include "throw.h"

namespace ssgi_cli {
namespace {

std::vector<CompareJob> plan_jobs(const CompareArgs& args) {
  std::vector<int> a_range, b_range;
  const ssgi::SequencePattern a = ssgi::parse_sequence_pattern(args.a, &a_range);
  const ssgi::SequencePattern b = ssgi::parse_sequence_pattern(args.b, &b_range);
  std::optional<ssgi::SequencePattern> diff;
  if (!args.idiff.diff_path.empty()) diff = ssgi::parse_sequence_pattern(args.idiff.diff_path);

  if (!a.has_frame_field && !b.has_frame_field) {
    if (!args.frames.empty()) ssgi::throw_usage("--frames needs a sequence pattern");
    if (diff && diff->has_frame_field)
      ssgi::throw_usage("-o has a frame field, but A and B are single files");
    return {CompareJob{std::nullopt, a.path_for(0), b.path_for(0), diff ? diff->path_for(0) : ""}};
  }
  // One side may be a single file, compared with every frame of the other.
  const ssgi::SequencePattern& sequence = a.has_frame_field ? a : b;
  std::vector<int> frames;
  if (!args.frames.empty())
    frames = ssgi::parse_frame_list(args.frames);
  else if (!a_range.empty())
    frames = a_range;
  else if (!b_range.empty())
    frames = b_range;
  else
    frames = ssgi::find_frames_on_disk(sequence);
  if (frames.empty())
    ssgi::throw_io(a.has_frame_field ? args.a : args.b, "no file on disk matches the pattern");
  if (diff && !diff->has_frame_field && frames.size() > 1)
    ssgi::throw_usage("-o needs a frame field (e.g. diff.####.exr) for a sequence");

  std::vector<CompareJob> jobs;
  for (int f : frames)
    jobs.push_back(CompareJob{f, a.path_for(f), b.path_for(f), diff ? diff->path_for(f) : ""});
  return jobs;
}

// Orders errors as their exit codes do: I/O (4) above input (3) above usage (2).
int severity(const ssgi::Error& e) {
  switch (e.kind()) {
    case ssgi::ErrorKind::kUsage:
      return 0;
    case ssgi::ErrorKind::kInput:
      return 1;
    case ssgi::ErrorKind::kIO:
    case ssgi::ErrorKind::kInternal:
      return 2;
  }
  return 2;
}

// The largest RMS error over a frame's subimages, which breaks ties between equal verdicts.
double worst_rms(const ssgi::IdiffFileResult& r) {
  double worst = -1.0;
  for (const ssgi::IdiffSubimage& s : r.subimages)
    worst = std::isnan(s.stats.rms_error) ? std::numeric_limits<double>::infinity()
                                          : std::max(worst, s.stats.rms_error);
  return worst;
}

}  // namespace

int run_compare(int argc, char** argv) {
  const std::optional<CompareArgs> parsed = parse_compare_args(argc, argv);
  if (!parsed) return kExitOk;
  const CompareArgs& args = *parsed;
  const std::vector<CompareJob> jobs = plan_jobs(args);

  std::optional<TextReport> text;
  if (!args.json) text.emplace(args);
  std::vector<FrameOutcome> frames;
  std::vector<ssgi::CompareResult> metrics;
  std::vector<int> metric_frame;  // frame number (0 for a single pair) of each entry of `metrics`
  std::array<int, 3> counts{};
  ssgi::CompareStatus status = ssgi::CompareStatus::kOk;
  std::optional<int> worst_frame;
  double worst_frame_rms = -1.0;
  // idiff pairs channels by index: say so once when the names differ and --channels could help.
  bool check_channel_names =
      args.idiff.channels.empty() && !args.idiff.all_subimages && !args.quiet;
  for (const CompareJob& job : jobs) {
    FrameOutcome outcome{job, std::nullopt, std::nullopt, std::nullopt};
    ssgi::IdiffOptions options = args.idiff;
    options.diff_path = job.diff;
    if (text) text->begin(job);
    try {
      outcome.idiff = ssgi::idiff_files(job.a, job.b, options);
      if (!args.metrics.empty()) outcome.metrics = ssgi::compare_files(job.a, job.b, args.file);
    } catch (const ssgi::Error& e) {
      // Usage errors are the same for every frame; a single pair reports its error as idiff does.
      if (e.kind() == ssgi::ErrorKind::kUsage || jobs.size() == 1) throw;
      outcome.idiff.reset();
      outcome.error = e;
    }
    if (text) text->frame(outcome);
    if (check_channel_names && outcome.idiff) {
      check_channel_names = false;
      std::fputs(channel_pairing_note(job.a, job.b).c_str(), stderr);
    }
    if (outcome.idiff) {
      const ssgi::CompareStatus s = outcome.idiff->status;
      ++counts[static_cast<int>(s)];
      const double rms = worst_rms(*outcome.idiff);
      if (!worst_frame || s > status || (s == status && rms > worst_frame_rms)) {
        status = std::max(status, s);
        worst_frame = job.frame.value_or(0);
        worst_frame_rms = rms;
      }
    }
    if (outcome.metrics) {
      metrics.push_back(outcome.metrics->result);
      metric_frame.push_back(job.frame.value_or(0));
    }
    frames.push_back(std::move(outcome));
  }
  const ssgi::Error* worst_error = nullptr;
  for (const FrameOutcome& f : frames) {
    if (f.error && (!worst_error || severity(*f.error) > severity(*worst_error)))
      worst_error = &*f.error;
  }

  const ssgi::SequenceSummary summary = ssgi::summarize_frames(metrics);
  if (text) {
    text->summary(frames, summary, counts, worst_frame, status);
  } else {
    std::printf("%s\n", json_report(args, frames, metric_frame, summary, counts, worst_frame,
                                    worst_error ? "error" : ssgi::status_name(status))
                            .c_str());
  }
  std::fflush(stdout);
  // main() reports the error and maps its kind to 3 (data) or 4 (file): above any verdict.
  if (worst_error) throw *worst_error;
  return static_cast<int>(status);
}

}  // namespace ssgi_cli
