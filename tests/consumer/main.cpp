// Parses a frame list and prints the library's version: enough to link against ssgi::ssgi.
#include <cstdio>

#include "ssgi/sequence.h"
#include "ssgi/version.h"

int main() {
  const auto frames = ssgi::parse_frame_list("1-5x2");
  std::printf("ssgi %s: %zu frames\n", ssgi::version(), frames.size());
  return frames.size() == 3 ? 0 : 1;
}
