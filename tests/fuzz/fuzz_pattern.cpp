// libFuzzer target: the sequence pattern and frame list parsers. The input up to the first
// newline is a pattern (shot.####.exr, shot.%04d.exr, shot.$F4.exr, shot.<UDIM>... with an
// optional range), the rest a --frames list ("1-10", "1,4,7-9x2"); the frames of each are
// turned into paths. An ssgi::Error is a refusal (fine); a crash, a sanitizer report, a hang
// or a list of frames that is empty, repeats one or holds over a million is a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include "io/sequence.h"
#include "ssgi/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto newline = text.find('\n');
  const std::string pattern = text.substr(0, newline);
  const std::string frames = newline == std::string::npos ? "" : text.substr(newline + 1);
  try {
    std::vector<int> range;
    const ssgi::SequencePattern p = ssgi::parse_sequence_pattern(pattern, &range);
    for (std::size_t i = 0; i < range.size() && i < 64; ++i) (void)p.path_for(range[i]);
  } catch (const ssgi::Error&) {
  }
  try {
    const std::vector<int> list = ssgi::parse_frame_list(frames);
    const std::set<int> unique(list.begin(), list.end());
    if (list.empty() || unique.size() != list.size() || list.size() > 1000000) {
      std::fprintf(stderr, "a list of %zu frames, %zu of them different\n", list.size(),
                   unique.size());
      std::abort();
    }
  } catch (const ssgi::Error&) {
  }
  return 0;
}
