// How many worker threads a run uses, and what decided it: --threads, else the scheduler's
// allocation, else the CPUs this process may run on.
#pragma once

#include <string>

#include "ssgi/threads.h"

namespace ssgi {

// How many worker threads a run uses, and what decided it.
struct ThreadBudget {
  int threads = 1;
  std::string source;  // "--threads", "SLURM_CPUS_PER_TASK", "CUE_THREADS", "cgroup cpu.max", ...
};

// `requested` > 0 (--threads) wins; else the scheduler's allocation: Slurm's
// SLURM_CPUS_PER_TASK, OpenCue's CUE_THREADS, the cgroup's CPU quota (cgroup v2 cpu.max, v1
// cpu.cfs_quota_us over cpu.cfs_period_us, rounded up); else the CPUs this process may run on.
// A farm node's core count is not what a task was given.
ThreadBudget thread_budget(int requested);

}  // namespace ssgi
