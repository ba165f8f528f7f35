// Where the library's warnings and progress notes go (the CLI prints them to stderr).
#pragma once

#include <functional>
#include <string>

namespace ssgi {

enum class LogLevel { kInfo, kWarning };

using LogHandler = std::function<void(LogLevel, const std::string&)>;

// Installs the handler for all later messages (default: discard). Not thread-safe to call
// while a run is in progress; messages themselves may come from any thread.
void set_log_handler(LogHandler handler);

void log_info(const std::string& message);
void log_warning(const std::string& message);

}  // namespace ssgi
