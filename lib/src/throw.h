// Throwing ssgi::Error in one call per kind, so that a call site reads as one line.
#pragma once

#include <string>

#include "ssgi/error.h"

namespace ssgi {

[[noreturn]] inline void throw_usage(const std::string& what) {
  throw Error(ErrorKind::kUsage, {}, what);
}
[[noreturn]] inline void throw_input(const std::string& file, const std::string& what) {
  throw Error(ErrorKind::kInput, file, what);
}
[[noreturn]] inline void throw_io(const std::string& file, const std::string& what) {
  throw Error(ErrorKind::kIO, file, what);
}

}  // namespace ssgi
