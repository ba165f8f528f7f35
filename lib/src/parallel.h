// The one wrapper around TBB: every parallel loop in the library goes through here.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

namespace ssgi::detail {

// Calls body(y) for every row y in [0, rows), in parallel. Rows are independent and each
// writes only its own outputs, so the result does not depend on the thread count.
template <typename Body>
void parallel_for_rows(int rows, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y < r.end(); ++y) body(y);
  });
}

// How many threads the loops above may use now (--threads, a ThreadLimit, or the machine's).
inline int worker_threads() {
  return static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace ssgi::detail
