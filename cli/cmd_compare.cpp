#include "commands.h"
namespace ssgi_cli {
int run_compare(int, char**) { return kExitUsage; }
}  // namespace ssgi_cli
