// The frame loop of a run (internal): each input decoded and lit (and, read twice, decoded again
// to be finished), filtered over the temporal ring, composited and written, its passed-through
// channels read from its file again, as a pipeline of frames in which reading the next input and
// writing the last output may overlap with computing the current one.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "frame_stages.h"
#include "io/frame_reader.h"
#include "io/input_frame.h"
#include "ssgi/io.h"

namespace ssgi::detail {

// Writes a frame the run made (the EXR, the preview): its G-buffer, its results (which it may
// convert in place) and its input's headers. Throws ssgi::Error.
using WriteMadeFrame = std::function<void(const GBuffer&, FrameResult&, const DecodedInput&)>;

struct SequenceJob {
  const SequenceInfo* sequence = nullptr;
  const InputOptions* input = nullptr;
  const FrameStages* pipeline = nullptr;
  std::vector<char> reuse;  // per frame of sequence->frames: already there, not made again
  std::function<std::string(int frame)> output_path;  // for the reports; "" when none
  WriteMadeFrame write;
  bool write_needs_passes = false;  // `write` reads the G-buffer's planes (the preview does)
  bool fail_fast = false;
  // Frames between reading and writing at once: 3 overlaps reading, computing and writing; 1
  // runs them one after the other (the least memory). PipelineMemory::frames_in_flight.
  int in_flight = 2;
  // The window's frames waiting for their later neighbours keep only their light on the trace
  // grid; each is decoded again to be finished. PipelineMemory::read_twice.
  bool read_twice = false;
};

// Runs `job` as run_sequence documents it (reports in frame order, callbacks on the calling
// thread). Frames the temporal stage needs besides those written (the window's neighbours on
// disk, the running average's pre-roll) are read and lit once each, and a frame's passes are
// kept only until it is written.
RunReport process_sequence(const SequenceJob& job, const RunCallbacks& callbacks);

// The ring the temporal stage keeps is bounded by its window: how many frames' G-buffers wait at
// most for their window's later frames, besides the frame being lit and those in flight (none
// when they are read twice).
int frames_waiting(TemporalMode mode, int temporal_radius, bool read_twice);

}  // namespace ssgi::detail
