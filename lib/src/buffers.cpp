// Blocks in huge pages for large buffers (Image's planes, the stages' own buffers).
#include "buffers.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ssgi::detail {
namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
// From here up a buffer is a frame-sized plane or more: 1 MB holds a 512 x 512 plane.
constexpr std::size_t kLargeBlock = std::size_t{1} << 20;

// The bytes allocate_block takes for a block of `bytes`: whole huge pages where the last one
// would be at least half used, so that it is a huge page too; otherwise `bytes`, its tail left
// in 4 KB pages, so that no block takes more than half a huge page beyond its size.
std::size_t block_bytes(std::size_t bytes) {
  const std::size_t tail = bytes % kHugePage;
  return tail >= kHugePage / 2 ? bytes - tail + kHugePage : bytes;
}

}  // namespace

// Each 4 KB page a buffer's first touch faults costs the kernel time, and a frame-sized buffer
// spans thousands of them; in 2 MB pages it faults 512 times less often (what that saves:
// tests/bench/README.md, "Huge pages"). Only the 2 MB pages inside the block are advised, so
// that nothing outside it is made resident; a kernel whose transparent huge pages are off
// ignores the advice.
void* allocate_block(std::size_t bytes) {
  if (bytes < kLargeBlock) return ::operator new(bytes);
  const std::size_t size = block_bytes(bytes);
  void* p = ::operator new (size, std::align_val_t{kHugePage});
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const std::size_t whole = size / kHugePage * kHugePage;
  if (whole > 0) madvise(p, whole, MADV_HUGEPAGE);
#endif
  return p;
}

void free_block(void* p, std::size_t bytes) noexcept {
  if (bytes < kLargeBlock)
    ::operator delete(p);
  else
    ::operator delete (p, std::align_val_t{kHugePage});
}

}  // namespace ssgi::detail
