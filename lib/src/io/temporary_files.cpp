#include "io/temporary_files.h"

#include <fcntl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include "throw.h"

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
constexpr int kDirectorySlots = 4;
Slot directory_slots[kDirectorySlots];

// Takes a free slot of `table` for `path`; -1 when none is free or the path is too long.
int register_path(Slot* table, int count, const std::string& path) noexcept {
  if (path.size() >= sizeof(Slot::path)) return -1;
  for (int i = 0; i < count; ++i) {
    int expected = 0;
    if (!table[i].state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    std::memcpy(table[i].path, path.c_str(), path.size() + 1);
    table[i].state.store(2, std::memory_order_release);
    return i;
  }
  return -1;
}

// Unlinks every file in `path`, then the directory, with system calls only: readdir may
// allocate, which a signal handler must not. getdents64 has no glibc wrapper before 2.30.
void remove_directory_in_handler(const char* path) noexcept {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    alignas(8) char buffer[4096];
    for (;;) {
      const long got = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer);
      if (got <= 0) break;
      for (long offset = 0; offset < got;) {
        struct Entry {
          std::uint64_t inode;
          std::int64_t next;
          unsigned short length;
          unsigned char type;
          char name[1];
        };
        const Entry* e = reinterpret_cast<const Entry*>(buffer + offset);
        const bool dots =
            e->name[0] == '.' && (e->name[1] == '\0' || (e->name[1] == '.' && e->name[2] == '\0'));
        if (!dots) ::unlinkat(fd, e->name, 0);
        offset += e->length;
      }
    }
    ::close(fd);
  }
  ::rmdir(path);
}

}  // namespace

void remove_temporary_files() noexcept {
  for (Slot& s : slots)
    if (s.state.load(std::memory_order_acquire) == 2) ::unlink(s.path);
  for (Slot& s : directory_slots)
    if (s.state.load(std::memory_order_acquire) == 2) remove_directory_in_handler(s.path);
}

TemporaryFile::TemporaryFile(const std::string& path) noexcept
    : slot_(register_path(slots, kSlots, path)) {}

TemporaryFile::~TemporaryFile() {
  if (slot_ >= 0) slots[slot_].state.store(0, std::memory_order_release);
}

TemporaryDirectory::TemporaryDirectory(const std::string& prefix) : slot_(-1) {
  std::error_code ec;
  std::filesystem::path base = std::filesystem::temp_directory_path(ec);
  if (ec) base = "/tmp";
  std::string name = (base / (prefix + "XXXXXX")).string();
  std::vector<char> buffer(name.begin(), name.end());
  buffer.push_back('\0');
  if (!::mkdtemp(buffer.data()))
    throw_io(name, std::string("cannot make a temporary directory: ") + std::strerror(errno));
  path_ = buffer.data();
  slot_ = register_path(directory_slots, kDirectorySlots, path_);
}

TemporaryDirectory::~TemporaryDirectory() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
  if (slot_ >= 0) directory_slots[slot_].state.store(0, std::memory_order_release);
}

std::string temporary_path_for(const std::string& path) {
  const std::filesystem::path target = std::filesystem::absolute(path);
  return (target.parent_path() / ("." + target.filename().string() + ".tmp" +
                                  std::to_string(::getpid()) + target.extension().string()))
      .string();
}

void move_into_place(const std::string& tmp, const std::string& path, const std::string& what) {
  std::error_code ec;
  std::filesystem::rename(tmp, std::filesystem::absolute(path), ec);
  if (!ec) return;
  const std::string why = ec.message();  // before remove() overwrites ec
  std::filesystem::remove(tmp, ec);
  throw_io(path, "cannot move the finished " + what + " into place: " + why);
}

void write_atomically(const std::string& path, const std::string& what,
                      const std::function<bool(const std::string& tmp, std::string* why)>& write) {
  const std::filesystem::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path(), ec);
  const std::string tmp = temporary_path_for(path);
  const TemporaryFile registered(tmp);  // before the file exists
  std::string why;
  if (write(tmp, &why)) return move_into_place(tmp, path, what);
  std::filesystem::remove(tmp, ec);
  throw_io(path, "cannot write the " + what + (why.empty() ? "" : ": " + why));
}

void write_text_atomically(const std::string& path, const std::string& text,
                           const std::string& what) {
  write_atomically(path, what, [&text](const std::string& tmp, std::string*) {
    std::ofstream file(tmp, std::ios::binary);
    file << text;
    file.flush();
    return file.good();
  });
}

}  // namespace ssgi
