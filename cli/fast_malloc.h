// The programs' allocator (cli/fast_malloc.cpp): oneTBB's scalable allocator, which keeps freed
// frame-sized blocks for reuse.
#pragma once

#include <cstdint>

namespace ssgi_cli {

// The allocator gives back every block it frees instead of keeping frame-sized ones for reuse:
// for a run under a memory limit or taking the least memory, whose peak is then its largest
// phase's rather than the phases' sum (pipeline_memory_within, PipelineMemory::freed_blocks_kept;
// at 1080p 371 against 617 MB). Nothing with glibc's allocator, which returns large blocks
// itself.
#if SSGI_FAST_MALLOC
void keep_no_freed_blocks();
#else
inline void keep_no_freed_blocks() {}
#endif

}  // namespace ssgi_cli
