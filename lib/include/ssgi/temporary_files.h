// ssgi writes every file under a hidden temporary name in its directory and renames it into
// place when it is complete, so that no file is ever seen half written under its own name.
// A program that stops on a signal removes the temporary files in flight from its handler.
#pragma once

#include <string>

namespace ssgi {

// Removes every temporary file being written right now. Async-signal-safe (it only calls
// unlink), for SIGINT and SIGTERM handlers; the files' writers must not go on afterwards.
void remove_temporary_files() noexcept;

// Registers `path` as a temporary file being written, for remove_temporary_files(), for as long
// as the object lives. Register before creating the file, so that no instant exists at which
// it is on disk but unknown. At most 64 at once; beyond, a file is written unregistered.
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& path) noexcept;
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

 private:
  int slot_;
};

}  // namespace ssgi
