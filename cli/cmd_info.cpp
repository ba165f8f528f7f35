#include "commands.h"
namespace ssgi_cli {
int run_info(int, char**) { return kExitUsage; }
}  // namespace ssgi_cli
