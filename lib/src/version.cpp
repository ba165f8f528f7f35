#include "ssgi/version.h"

namespace ssgi {

const char* version() { return SSGI_VERSION_STRING; }

}  // namespace ssgi
