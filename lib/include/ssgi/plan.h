// What a frame's pipeline is made from (its sequence) and a run's memory limit.
#pragma once

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

// A memory limit and what set it; bytes 0: none.
struct MemoryLimit {
  std::uint64_t bytes = 0;
  std::string source;  // "--max-memory", "SLURM_MEM_PER_NODE", "cgroup v2 memory.max (path)"
};

}  // namespace ssgi
