#include "log.h"

#include <mutex>

namespace ssgi {
namespace {

LogHandler& handler() {
  static LogHandler h;
  return h;
}

std::mutex& log_mutex() {
  static std::mutex m;
  return m;
}

void emit(LogLevel level, const std::string& message) {
  // Serialised so that lines from worker threads never interleave.
  std::lock_guard<std::mutex> lock(log_mutex());
  if (handler()) handler()(level, message);
}

}  // namespace

void set_log_handler(LogHandler h) { handler() = std::move(h); }
void log_info(const std::string& message) { emit(LogLevel::kInfo, message); }
void log_warning(const std::string& message) { emit(LogLevel::kWarning, message); }

}  // namespace ssgi
