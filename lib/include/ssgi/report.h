// What became of each frame of a run, and what a run tells its caller as it goes.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "ssgi/error.h"
#include "ssgi/gbuffer.h"

namespace ssgi {

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

}  // namespace ssgi
