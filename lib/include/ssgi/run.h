// A whole `ssgi run`: read, process and write every requested frame.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ssgi/error.h"
#include "ssgi/io.h"
#include "ssgi/settings.h"

namespace ssgi {

struct RunOptions {
  InputOptions input;
  std::string output;  // output pattern, e.g. "out/shot.####.exr"
  WriteOptions write;
  GiSettings gi;
  bool fail_fast = false;  // --fail-fast: stop at the first frame that fails
};

// What became of one frame.
struct FrameReport {
  int frame = 0;
  std::string input, output;
  bool ok = false;
  ErrorKind error_kind = ErrorKind::kInternal;  // when !ok
  std::string error_file, error;                // when !ok
  double seconds = 0;                           // read + process + write
  // Milliseconds: decoding and converting inputs (the frame's and its window's new
  // neighbours'), everything between those and the frame ready to encode (tracing, bounces,
  // denoise, temporal, composite), and encoding and writing.
  double read_ms = 0, gi_ms = 0, write_ms = 0;
};

struct RunReport {
  std::vector<FrameReport> frames;  // those attempted, in order
  int total = 0;                    // the frames the run was to write
  int failed() const;
};

// Called after each frame, from the thread that called run_sequence.
using FrameCallback = std::function<void(const FrameReport&, int done, int total)>;

// Runs the pipeline over the sequence. Errors that concern the whole run (bad options, a
// pattern matching nothing, an output that would overwrite an input) are thrown as
// ssgi::Error before any frame is written; an error in one frame is recorded in its report
// and the other frames go on.
RunReport run_sequence(const RunOptions& options, const FrameCallback& on_frame);

}  // namespace ssgi
