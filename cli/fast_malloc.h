// The programs' allocator (cli/fast_malloc.cpp): oneTBB's scalable allocator, which keeps freed
// frame-sized blocks for reuse unless told otherwise.
#pragma once

#include <cstdint>

namespace ssgi_cli {

// The allocator gives back every block it frees instead of keeping frame-sized ones for reuse,
// so that a run's peak is its largest phase's (estimate_run_memory) rather than the phases'
// sum: a farm slot is sized by the peak. Kept, the blocks save page faults but add one phase's
// planes to the next (both measured in tests/bench/README.md, "Rendered 1080p and 4K", the
// table of the program's allocator). Nothing with glibc's allocator, which returns large blocks
// itself.
#if SSGI_FAST_MALLOC
void keep_no_freed_blocks();
#else
inline void keep_no_freed_blocks() {}
#endif

}  // namespace ssgi_cli
