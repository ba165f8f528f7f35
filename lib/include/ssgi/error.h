// The one exception type the library throws; the CLI maps its kind to an exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace ssgi {

// What went wrong, coarse enough to pick an exit code from (see man/ssgi.1, EXIT STATUS).
enum class ErrorKind {
  kUsage,     // bad option or argument value
  kInput,     // input data unusable: missing channel, bad camera, inconsistent sequence
  kIO,        // file missing, unreadable, truncated, not writable
  kInternal,  // a bug: an invariant did not hold
};

// An error with its kind and the file it is about: what every function of the library throws.
class Error : public std::runtime_error {
 public:
  // `file` is the file the problem is about, or empty when there is none.
  Error(ErrorKind kind, std::string file, const std::string& what)
      : std::runtime_error(what), kind_(kind), file_(std::move(file)) {}

  ErrorKind kind() const { return kind_; }
  const std::string& file() const { return file_; }

 private:
  ErrorKind kind_;
  std::string file_;
};

}  // namespace ssgi
