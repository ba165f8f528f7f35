// A run's memory plan: its limit, the frames in flight and the reading that fit it, and the
// estimated peak; `ssgi run` refuses a run over the limit, `ssgi info` reports the same plan.
#pragma once

#include <string>

#include "io/frame_reader.h"
#include "memory.h"
#include "plan.h"
#include "ssgi/settings.h"

namespace ssgi {

// What a run of a sequence with given settings will hold, and under which limit.
struct MemoryPlan {
  MemoryLimit limit;               // bytes 0: none
  int frames_in_flight_asked = 0;  // --frames-in-flight; 0: not asked
  PipelineMemory memory;           // what the run uses: frames in flight, read twice, hits kept
  MemoryEstimate estimate;         // the peak with `memory`
  bool over_limit() const { return limit.bytes != 0 && estimate.bytes > limit.bytes; }
  // Why `memory` is what it is: "to fit the limit" (fewer frames in flight or read twice),
  // "within the limit", "as asked", or the least memory without a limit
  // (pipeline_memory_within).
  std::string reason() const;
};

// The memory plan of a run of `sequence` with `gi` and `write` on the library's worker threads
// (threads.h) under `limit`, with up to `frames_in_flight` frames in flight (0: the default).
// RunOptions' own fields, given one by one: run.cpp includes this header, which therefore
// cannot include ssgi/run.h (tests/layering_test.py would find a circle).
// Throws what make_plan throws.
MemoryPlan plan_run_memory(const SequenceInfo& sequence, const GiSettings& gi,
                           const WriteOptions& write, const MemoryLimit& limit,
                           int frames_in_flight, bool passes_read_after_composite = false);

// "500 MiB from --max-memory", or "none (no --max-memory, no scheduler limit)".
std::string memory_limit_text(const MemoryLimit& limit);

}  // namespace ssgi
