// What a frame's pipeline is made from (its sequence, what it may hold) and a run's memory limit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "ssgi/gbuffer.h"

namespace ssgi {

// A sequence as the library's reader finds it on disk (its windows, frames, channels, layout
// and views), opaque to programs: a run opens its own, still_sequence makes one for buffers.
struct SequenceInfo;

// The sequence of one frame given as buffers, read from no file: the windows of `frame` and the
// passes it holds (its non-empty images), no other frame (no temporal stage), no views. Throws
// Error(kUsage) unless depth has 1 channel and normal, albedo, direct 3, over the data window.
std::shared_ptr<const SequenceInfo> still_sequence(const GBuffer& frame);

// A run's colour spaces (GiSettings::color) and the processors between them, opaque to programs.
class ColorManagement;

// What a run does (the stages, the passes read), decided once; opaque to programs.
struct Plan;

// What the pipeline and a run may hold besides the frames' planes (a run chooses it for its
// memory limit). It does not change the light.
struct PipelineMemory {
  // The bytes of hits (4 a ray) the Embree reference keeps for the bounces after the first; the
  // rows beyond them are traced again for each bounce.
  std::size_t reference_hits_bytes = std::size_t{1} << 30;
  // Frames read, lit and written at once: 3 reads the next and writes the last while lighting
  // one, 2 overlaps two of those, 1 does one after the other.
  int frames_in_flight = 2;
  // The window's frames waiting for their later neighbours hold only their light on the trace
  // grid and are decoded again to be finished: the least memory, the same bits.
  bool read_twice = false;
  // A frame's passes are read after its composite (a callback, the preview), which is then
  // written beside them rather than over them.
  bool passes_read_after_composite = false;
};

// A memory limit and what set it; bytes 0: none.
struct MemoryLimit {
  std::uint64_t bytes = 0;
  std::string source;  // "--max-memory", "SLURM_MEM_PER_NODE", "cgroup v2 memory.max (path)"
};

}  // namespace ssgi
