// Linked into ssgi's programs and benchmarks with oneTBB's malloc proxy (CMakeLists.txt,
// ssgi_fast_malloc): frame-sized blocks (a 1080p plane is 8 MB) count as "huge" from 1 MB up,
// and huge blocks are kept for reuse instead of going back to the kernel, so a frame's planes do
// not start as fresh zeroed pages (tests/bench/README.md, "The allocator"). The ssgi program
// itself then gives them back (keep_no_freed_blocks).
#include "fast_malloc.h"

#include <oneapi/tbb/scalable_allocator.h>

namespace {

const bool kHugeBlocksKept = [] {
  scalable_allocation_mode(TBBMALLOC_SET_HUGE_SIZE_THRESHOLD, 1 << 20);
  return true;
}();

}  // namespace

namespace ssgi_cli {

void keep_no_freed_blocks() {
  // A soft heap limit the process is always over has the allocator give back what it can.
  scalable_allocation_mode(TBBMALLOC_SET_SOFT_HEAP_LIMIT, 1);
  // And no frame-sized block kept for reuse, so that the peak is the largest phase's
  // (fast_malloc.h).
  scalable_allocation_mode(TBBMALLOC_SET_HUGE_SIZE_THRESHOLD, static_cast<intptr_t>(1) << 40);
}

}  // namespace ssgi_cli
