// The programs' allocator (cli/fast_malloc.cpp): oneTBB's scalable allocator, which keeps freed
// frame-sized blocks for reuse unless told otherwise.
#pragma once

#include <cstdint>

namespace ssgi_cli {

// The allocator gives back every block it frees instead of keeping frame-sized ones for reuse,
// so that a run's peak is its largest phase's (estimate_run_memory) rather than the phases'
// sum: a farm slot is sized by the peak. Kept, the blocks saved page faults but added one
// phase's planes to the next (1080p rendered shot, --frames-in-flight 2: 1065 MiB measured
// against 933 MiB of the phases' largest; tests/bench/rendered.sh). Nothing with glibc's
// allocator, which returns large blocks itself.
#if SSGI_FAST_MALLOC
void keep_no_freed_blocks();
#else
inline void keep_no_freed_blocks() {}
#endif

}  // namespace ssgi_cli
