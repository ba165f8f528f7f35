// Limits the library's worker threads for as long as the object lives (--threads).
#pragma once

#include <memory>

namespace ssgi {

class ThreadLimit {
 public:
  // `threads` > 0 caps the library's parallelism (and OIIO's and OpenEXR's); 0 leaves it.
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ssgi
