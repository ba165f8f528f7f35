// Where the library's warnings and progress notes go (the CLI prints them to stderr).
#pragma once

#include <functional>
#include <string>

namespace ssgi {

// A progress note (the CLI prints it with -v) or a warning (printed unless -q).
enum class LogLevel { kInfo, kWarning };

// Takes each message the library logs, with its level.
using LogHandler = std::function<void(LogLevel, const std::string&)>;

// Installs the handler for all later messages (default: discard). Not thread-safe to call
// while a run is in progress; messages themselves may come from any thread.
void set_log_handler(LogHandler handler);

}  // namespace ssgi
