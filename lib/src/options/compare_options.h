// `ssgi compare`'s options: idiff's, spelled as idiff spells them, and ssgi's metrics.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "compare/idiff.h"
#include "ssgi/compare.h"

namespace ssgi_cli {

// What the command line asks for.
struct CompareArgs {
  std::string a, b;
  std::string frames;
  bool verbose = false, quiet = false, json = false;
  std::vector<ssgi::Metric> metrics;  // empty: idiff's numbers only
  ssgi::IdiffOptions idiff;
  ssgi::FileCompareOptions file;  // ssgi's metrics
};

// Parses `ssgi compare`'s arguments (idiff's options and ssgi's). Returns nullopt after
// printing --help; throws Error(kUsage) for anything it cannot take.
std::optional<CompareArgs> parse_compare_args(int argc, char** argv);

// Parses a comma list of metric names ("all" for every metric), in the order given without
// repeats. Throws Error(kUsage) on an unknown or missing name.
std::vector<ssgi::Metric> parse_metric_list(const std::string& list);

}  // namespace ssgi_cli
