// A whole `ssgi run`: read, process and write every requested frame.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ssgi/error.h"
#include "ssgi/io.h"
#include "ssgi/memory.h"
#include "ssgi/pipeline.h"
#include "ssgi/settings.h"

namespace ssgi {

struct RunOptions {
  InputOptions input;
  // Output pattern, e.g. "out/shot.####.exr"; empty: no frame is written (the results go to
  // RunCallbacks::on_result only).
  std::string output;
  // --preview: each frame's composite through the display and view, e.g. "prev.####.png"
  // (.png or .jpg), the size of the display window; empty: none.
  std::string preview;
  WriteOptions write;
  GiSettings gi;
  bool fail_fast = false;  // --fail-fast: stop at the first frame that fails
  // --skip-existing: a frame whose output exists, reads whole and was made by this version of
  // ssgi with these settings (its header says) is not made again.
  bool skip_existing = false;
  // --no-clobber: refuse the run, before any frame is computed, when it would overwrite a file.
  bool no_clobber = false;
  // --max-memory, else the scheduler's (scheduler_memory_limit): a run whose estimated peak
  // (estimate_run_memory) is over it is refused before anything is computed or written.
  MemoryLimit memory_limit;
  // --frames-in-flight: frames read, lit and written at once (1 to 3; 0: PipelineMemory's
  // default), fewer when the memory limit needs it.
  int frames_in_flight = 0;
};

// What became of one frame.
struct FrameReport {
  int frame = 0;
  std::string input, output;
  bool ok = false;
  bool skipped = false;                         // ok: the output was already there (skip_existing)
  ErrorKind error_kind = ErrorKind::kInternal;  // when !ok
  std::string error_file, error;                // when !ok
  // The frame's own work, read + process + write (run_sequence reads, lights and writes
  // different frames at once, so a run takes less than the sum over its frames).
  double seconds = 0;
  // Milliseconds of the frame's own work: decoding and converting its input, everything
  // between that and the frame ready to encode (tracing, bounces, denoise, temporal,
  // composite), and encoding and writing. A frame read only for the temporal stage (a window's
  // neighbour outside the frames asked for, the running average's pre-roll) counts with the
  // frame it serves.
  double read_ms = 0, gi_ms = 0, write_ms = 0;
  std::size_t sanitized = 0;  // input values that were NaN or infinite, read as 0
};

struct RunReport {
  std::vector<FrameReport> frames;  // those attempted, in order
  int total = 0;                    // the frames the run was to write
  int failed() const;
  int skipped() const;
};

// What run_sequence tells its caller as it goes, from the thread that called it.
struct RunCallbacks {
  // Once the frames are known, before any is computed: how many the run is to write, and how
  // many of those are already there (skip_existing) and will not be made again.
  std::function<void(int total, int reused)> on_start;
  // After each frame, written, reused or failed; `done` frames of `total` are behind.
  std::function<void(const FrameReport&, int done, int total)> on_frame;
  // Each frame made (not those reused), before it is written: its G-buffer (without the motion
  // passes, which only the temporal stage reads) and results, the colour passes and results in
  // the working space.
  std::function<void(const GBuffer&, const FrameResult&)> on_result;
};

// Runs the pipeline over the sequence: each input decoded once, and while one frame is lit the
// next is read and the last written (as many frames in flight as the memory limit allows).
// Errors that concern the whole run (bad options, a
// pattern matching nothing, an output that would overwrite an input, or with no_clobber any
// existing output it would write again) are thrown as ssgi::Error before any frame is written;
// an error in one frame is recorded in its report and the other frames go on.
RunReport run_sequence(const RunOptions& options, const RunCallbacks& callbacks = {});

}  // namespace ssgi
