// The parts of `ssgi compare` (cmd_compare.cpp runs them) besides its options
// (options/compare_options.h): the report of its results as idiff's text or as JSON, and the
// note on channels paired by index.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "compare/compare.h"
#include "compare/compare_files.h"
#include "options/compare_options.h"
#include "ssgi/error.h"

namespace ssgi_cli {

// What to compare: one pair of files per frame, or a single pair.
struct CompareJob {
  std::optional<int> frame;
  std::string a, b, diff;
};

// One frame's outcome: results, or the error that stopped it.
struct FrameOutcome {
  CompareJob job;
  std::optional<ssgi::IdiffFileResult> idiff;
  std::optional<ssgi::FileCompareResult> metrics;  // with --metric
  std::optional<ssgi::Error> error;
};

// The text idiff prints, line for line, then ssgi's metrics (marked "ssgi") before the verdict.
class TextReport {
 public:
  explicit TextReport(const CompareArgs& args) : args_(args) {}

  // Before the files are read, as idiff does.
  void begin(const CompareJob& job);

  void frame(const FrameOutcome& f);

  // After a sequence: ssgi's metrics' mean and worst, the count per verdict, the verdict.
  void summary(const std::vector<FrameOutcome>& frames, const ssgi::SequenceSummary& s,
               const std::array<int, 3>& counts, std::optional<int> worst_frame,
               ssgi::CompareStatus status);

 private:
  void subimage(const ssgi::IdiffSubimage& s);
  void metrics_line(const ssgi::FileCompareResult& r, const ssgi::LayerStats& layer);
  void verdict(ssgi::CompareStatus status);

  const CompareArgs& args_;
};

// The results as one JSON document (--json): the options, every frame, the summary.
std::string json_report(const CompareArgs& args, const std::vector<FrameOutcome>& frames,
                        const std::vector<int>& metric_frame, const ssgi::SequenceSummary& summary,
                        const std::array<int, 3>& counts, std::optional<int> worst_frame,
                        const char* status);

// When A's and B's first subimages name their channels differently (idiff pairs them by
// index), two lines for stderr that say which names were paired and, where the channel names'
// layers can be matched, the --channels argument that pairs them by name. Empty when the names
// agree or a file cannot be read.
std::string channel_pairing_note(const std::string& a_path, const std::string& b_path);

}  // namespace ssgi_cli
