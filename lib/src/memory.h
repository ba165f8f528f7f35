// A run's memory: the limit it must fit in (--max-memory, else the scheduler's allocation) and
// the peak it is estimated to need from its plan, checked before any frame is computed.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>

#include "io/frame_reader.h"
#include "plan.h"
#include "ssgi/settings.h"

namespace ssgi {

// "500M", "2G", "1.5G", "64K", "2T" or plain bytes ("123456"); K, M, G and T are powers of 1024
// (as Slurm's --mem and cgroups count), an optional trailing "B" or "iB" is allowed. Throws
// Error(kUsage) naming --max-memory for anything else, or 0.
std::uint64_t parse_memory_size(const std::string& text);

// Bytes for people: "512 MiB", "1.5 GiB".
std::string memory_size_text(std::uint64_t bytes);

// Where the scheduler's limits are looked for; tests point them at files of their own.
struct MemoryLimitSources {
  std::string cgroup_root = "/sys/fs/cgroup";
  std::string self_cgroup = "/proc/self/cgroup";  // which cgroup this process is in
  std::function<const char*(const char*)> getenv = [](const char* name) {
    return std::getenv(name);
  };
};

// The scheduler's memory limit: the smallest of Slurm's allocation (SLURM_MEM_PER_NODE, or
// SLURM_MEM_PER_CPU x SLURM_CPUS_PER_TASK (1 when unset), in MiB as Slurm gives them) and the
// cgroup's (v2 memory.max of this process's cgroup and its ancestors, "max" being none; v1
// memory.limit_in_bytes). None when no source sets one.
MemoryLimit scheduler_memory_limit(const MemoryLimitSources& sources = {});

// The peak resident memory a run is estimated to need, and of what it is made.
struct MemoryEstimate {
  std::uint64_t bytes = 0;
  std::string parts;  // "frames 120 MiB, tracing 40 MiB, ...", for -v and the refusal
};

// An upper bound on the peak of a run of `sequence` with `plan` and `settings` on `threads`
// workers (the frames the temporal window keeps, a frame's planes while it is lit, finished and
// written, the tracer's hits and scene, the denoiser, the writer's strips, and the frames in
// flight besides the one lit: memory.frames_in_flight), from the first frame's header alone.
// How far above the measured peaks it lies: tests/bench/README.md, "Rendered 1080p and 4K" and
// "The memory estimate".
MemoryEstimate estimate_run_memory(const SequenceInfo& sequence, const Plan& plan,
                                   const GiSettings& settings, const WriteOptions& write,
                                   int threads, const PipelineMemory& memory);

// The pipeline's memory for a run under `limit`. Without a limit: `frames_in_flight` when it is
// asked for (1 to 3) with the window's waiting frames kept, else the least the run can take: one
// frame in flight and, in the window mode, each frame decoded again to be finished
// (PipelineMemory::read_twice). Under a limit, the fastest that fits: as many frames in flight
// (up to `frames_in_flight`, else 2) as the estimate fits, and when one does not, the window's
// frames read twice with as many. The reference keeps at most 1 GiB of hits, and no more than
// what the limit leaves beside the rest of the run (as little as none: then each bounce traces
// again). `passes_read_after_composite` is PipelineMemory's.
PipelineMemory pipeline_memory_within(const MemoryLimit& limit, const SequenceInfo& sequence,
                                      const Plan& plan, const GiSettings& settings,
                                      const WriteOptions& write, int threads,
                                      int frames_in_flight = 0,
                                      bool passes_read_after_composite = false);

}  // namespace ssgi
