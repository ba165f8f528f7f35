// The library's own messages, given to the program's log handler (ssgi/log.h).
#pragma once

#include <string>

#include "ssgi/log.h"

namespace ssgi {

// A progress note: what was decided and why, what took how long.
void log_info(const std::string& message);
// Something the user should know: a result may not be what they expect.
void log_warning(const std::string& message);

}  // namespace ssgi
