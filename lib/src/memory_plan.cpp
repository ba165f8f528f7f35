// A run's memory plan, worked out once for `ssgi run` and `ssgi info`.
#include "memory_plan.h"

#include <algorithm>

#include "parallel.h"

namespace ssgi {

MemoryPlan plan_run_memory(const SequenceInfo& seq, const GiSettings& gi, const WriteOptions& write,
                           const MemoryLimit& limit, int frames_in_flight,
                           bool passes_read_after_composite) {
  const Plan plan = make_plan(seq, gi);
  const int threads = detail::worker_threads();
  MemoryPlan m;
  m.limit = limit;
  m.frames_in_flight_asked = std::max(0, frames_in_flight);
  m.memory = pipeline_memory_within(limit, seq, plan, gi, write, threads, m.frames_in_flight_asked,
                                    passes_read_after_composite);
  m.estimate = estimate_run_memory(seq, plan, gi, write, threads, m.memory);
  return m;
}

std::string MemoryPlan::reason() const {
  if (limit.bytes) {
    const int most = frames_in_flight_asked > 0 ? frames_in_flight_asked : 2;
    return memory.frames_in_flight < most || memory.read_twice ? "to fit the limit"
                                                               : "within the limit";
  }
  if (frames_in_flight_asked > 0) return "as asked";
  return "the least memory, without a limit; a --max-memory above it lets the run overlap "
         "frames and keep the window's, to go faster";
}

std::string memory_limit_text(const MemoryLimit& limit) {
  return limit.bytes ? memory_size_text(limit.bytes) + " from " + limit.source
                     : std::string("none (no --max-memory, no scheduler limit)");
}

}  // namespace ssgi
