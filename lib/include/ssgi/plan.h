// What a run does, decided once from what the inputs provide and what the user asked.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ssgi/io.h"
#include "ssgi/settings.h"

namespace ssgi {

// What a run does, decided once from what the inputs provide and what the user asked: the
// only place that chooses stages, channels and buffers.
struct Plan {
  RoleMask roles = 0;            // the channels the reader reads
  bool gather_emission = false;  // emission is part of the light rays pick up
  int trace_scale = 1;           // data-window pixels per trace sample, each axis
  bool env_map = false;          // misses look up an environment map
  bool denoise = false;
  TemporalMode temporal = TemporalMode::kNone;
  int multiframe = 0;                // frames each side that missed rays are continued in (0: none)
  bool views = false;                // missed rays continued in the shot's views (--view) first
  std::vector<std::string> reasons;  // one line per decision, for `ssgi info` and -v
  std::vector<std::string> warnings;  // what `ssgi run` and `ssgi info` warn about, one line each
};

// Decides the plan for `sequence` under `settings`.
Plan make_plan(const SequenceInfo& sequence, const GiSettings& settings);

// What the pipeline may hold besides its frames' planes. It does not change the light.
struct PipelineMemory {
  // The Embree reference keeps, for the bounces after the first, the hits of as many rows as
  // fit in this many bytes (4 per ray), and traces the other rows again for each bounce.
  std::size_t reference_hits_bytes = std::size_t{1} << 30;
  // Frames between reading and writing at once in run_sequence: 3 reads the next frame and
  // writes the last while lighting one; 2 overlaps two of those; 1 does one after the other.
  // pipeline_memory_within chooses (1 without a limit, the least memory).
  int frames_in_flight = 2;
  // The symmetric window finishes a frame only after its later neighbours are lit. Kept, a frame
  // waiting for them holds its full-resolution passes; read twice, it holds only its light on
  // the trace grid and is decoded again to be finished: the least memory, for a second decoding
  // of each frame written (the same bits either way).
  bool read_twice = false;
  // Whether a frame's passes are read after its composite (a callback, the preview): the
  // composite is then written beside them rather than over them.
  bool passes_read_after_composite = false;
};

// A memory limit and what set it; bytes 0: none.
struct MemoryLimit {
  std::uint64_t bytes = 0;
  std::string source;  // "--max-memory", "SLURM_MEM_PER_NODE", "cgroup v2 memory.max (path)"
};

}  // namespace ssgi
