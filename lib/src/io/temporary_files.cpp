#include "ssgi/temporary_files.h"

#include <unistd.h>

#include <atomic>
#include <cstring>

namespace ssgi {
namespace {

// A fixed table, so that the signal handler reads it without locks or allocation. A slot is
// free (0), being filled (1) or holds a path to remove (2).
struct Slot {
  std::atomic<int> state{0};
  char path[4096];
};
constexpr int kSlots = 64;
Slot slots[kSlots];

}  // namespace

void remove_temporary_files() noexcept {
  for (Slot& s : slots)
    if (s.state.load(std::memory_order_acquire) == 2) ::unlink(s.path);
}

TemporaryFile::TemporaryFile(const std::string& path) noexcept : slot_(-1) {
  if (path.size() >= sizeof(Slot::path)) return;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (!slots[i].state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    std::memcpy(slots[i].path, path.c_str(), path.size() + 1);
    slots[i].state.store(2, std::memory_order_release);
    slot_ = i;
    return;
  }
}

TemporaryFile::~TemporaryFile() {
  if (slot_ >= 0) slots[slot_].state.store(0, std::memory_order_release);
}

}  // namespace ssgi
