// ssgi writes every file under a hidden temporary name in its directory and renames it into
// place when it is complete, so that no file is ever seen half written under its own name.
// A program that stops on a signal removes the temporary files in flight from its handler.
#pragma once

#include <functional>
#include <string>

namespace ssgi {

// Removes every temporary file being written right now, then every registered temporary
// directory with the files in it. Async-signal-safe (open, getdents64, unlink, unlinkat,
// rmdir, close), for SIGINT and SIGTERM handlers; the writers must not go on afterwards.
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

// A private directory (mode 0700) for a program's scratch files, made under the system's
// temporary directory ($TMPDIR, else /tmp) and removed with the files in it when the object
// goes, on an exception too, or by remove_temporary_files() on a signal. It must hold only
// files, no subdirectories. At most 4 at once; beyond, one is made unregistered.
class TemporaryDirectory {
 public:
  // Makes `<tmp>/<prefix>XXXXXX`. Throws Error(kIO) when it cannot be made.
  explicit TemporaryDirectory(const std::string& prefix);
  ~TemporaryDirectory();
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int slot_;
};

// The hidden name `path` is written under: in its directory, with the process id (two
// processes writing one file do not share it) and the extension kept (it tells OIIO the format).
std::string temporary_path_for(const std::string& path);

// Renames the finished temporary file `tmp` to `path`. On failure removes `tmp` and throws
// Error(kIO) naming `path`: "cannot move the finished <what> into place: <why>".
void move_into_place(const std::string& tmp, const std::string& path, const std::string& what);

// Makes the missing directories of `path`, lets `write` write the temporary file it is given
// (temporary_path_for; false on failure, with *why saying what went wrong if it knows), and
// moves that into place. The temporary file is registered for remove_temporary_files() and
// removed on failure. Throws Error(kIO) naming `path`: "cannot write the <what>[: why]". The
// frames and difference images go through io/oiio_files.h's AtomicImageWriter, which uses the
// same two steps.
void write_atomically(const std::string& path, const std::string& what,
                      const std::function<bool(const std::string& tmp, std::string* why)>& write);

// `text` as the whole file, atomically.
void write_text_atomically(const std::string& path, const std::string& text,
                           const std::string& what);

}  // namespace ssgi
