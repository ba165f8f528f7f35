// The library's worker threads: a limit on how many, for as long as an object lives.
#pragma once

#include <memory>

namespace ssgi {

// How many threads the limit allows and what decided it, opaque to programs.
struct ThreadBudget;

// A cap on the library's worker threads (and OIIO's and OpenEXR's) while the object lives.
class ThreadLimit {
 public:
  // `requested` > 0 (--threads) threads; 0: the scheduler's allocation (Slurm, OpenCue, the
  // cgroup's CPU quota), else the CPUs this process may run on.
  explicit ThreadLimit(int requested);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

  const ThreadBudget& budget() const;  // the threads allowed and what decided it

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ssgi
