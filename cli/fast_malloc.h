// The programs' allocator (cli/fast_malloc.cpp): oneTBB's scalable allocator, which keeps freed
// frame-sized blocks for reuse.
#pragma once

#include <cstdint>

namespace ssgi_cli {

// Under a memory limit for the whole process: the allocator keeps no frame-sized block for
// reuse, and gives the smaller ones it keeps back to the kernel whenever it holds more than the
// limit leaves beside what the process holds now (its libraries), so that its cache never takes
// a run over the limit (at 1080p it would keep each phase's planes: 600 against 440 MB
// measured). Nothing with glibc's allocator, which
// returns large blocks itself.
// A process_bytes of 0 is no limit: the allocator then keeps what it frees, for speed, unless
// `least` (a run without a limit takes the least memory: pipeline_memory_within), when it gives
// back all it can.
#if SSGI_FAST_MALLOC
void keep_allocator_within(std::uint64_t process_bytes, bool least = false);
#else
inline void keep_allocator_within(std::uint64_t, bool = false) {}
#endif

}  // namespace ssgi_cli
