// Linked into ssgi's programs with oneTBB's malloc proxy (CMakeLists.txt, ssgi_fast_malloc):
// frame-sized blocks (a 1080p plane is 8 MB) count as "huge" from 1 MB up, and huge blocks
// are kept for reuse instead of going back to the kernel, so a frame's planes do not start as
// fresh zeroed pages (measured at 1080p: the composite 45 -> 22 ms, page faults 1.06 M -> 0.31
// M over the same benchmark run).
#include <oneapi/tbb/scalable_allocator.h>

namespace {

const bool kHugeBlocksKept = [] {
  scalable_allocation_mode(TBBMALLOC_SET_HUGE_SIZE_THRESHOLD, 1 << 20);
  return true;
}();

}  // namespace
