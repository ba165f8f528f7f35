#include "threads.h"

#include <sched.h>
#include <tbb/global_control.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "io/frame_reader.h"

namespace ssgi {
namespace {

// A positive whole number from the environment variable `name`, else 0.
int positive_env(const char* name) {
  const char* text = std::getenv(name);
  if (text == nullptr || *text == '\0') return 0;
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  return errno == 0 && *end == '\0' && v > 0 && v <= 65536 ? static_cast<int>(v) : 0;
}

// The CPU quota of this process's cgroup, in whole CPUs rounded up; 0 when unlimited or unknown.
int cgroup_cpus() {
  auto cpus = [](double quota, double period) {
    return quota > 0 && period > 0 ? static_cast<int>(std::ceil(quota / period)) : 0;
  };
  std::ifstream v2("/sys/fs/cgroup/cpu.max");  // "max 100000" or "200000 100000"
  std::string quota;
  double period = 0;
  if (v2 >> quota >> period) return quota == "max" ? 0 : cpus(std::atof(quota.c_str()), period);
  std::ifstream q1("/sys/fs/cgroup/cpu/cpu.cfs_quota_us"),
      p1("/sys/fs/cgroup/cpu/cpu.cfs_period_us");
  double q = 0, p = 0;
  if (q1 >> q && p1 >> p) return cpus(q, p);  // a quota of -1: unlimited
  return 0;
}

// The CPUs this process may run on (its affinity mask), at least 1.
int affinity_cpus() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return 1;
}

}  // namespace

ThreadBudget thread_budget(int requested) {
  if (requested > 0) return {requested, "--threads"};
  for (const char* name : {"SLURM_CPUS_PER_TASK", "CUE_THREADS"})
    if (const int n = positive_env(name)) return {n, name};
  const int affinity = affinity_cpus();
  if (const int n = cgroup_cpus(); n > 0 && n < affinity) return {n, "cgroup CPU quota"};
  return {affinity, "the CPUs this process may use"};
}

struct ThreadLimit::Impl {
  ThreadBudget budget;
  std::unique_ptr<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int requested) : impl_(std::make_unique<Impl>()) {
  impl_->budget = thread_budget(requested);
  impl_->control =
      std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                            static_cast<std::size_t>(impl_->budget.threads));
  set_io_threads(impl_->budget.threads);
}

ThreadLimit::~ThreadLimit() = default;

const ThreadBudget& ThreadLimit::budget() const { return impl_->budget; }

}  // namespace ssgi
