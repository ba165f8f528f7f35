#include "truth_layer.h"

#include <algorithm>
#include <vector>

#include "throw.h"

namespace ssgi_cli {
namespace {

// Every channel of a file under the name ssgi compare knows it by (a named part's plain
// channels as <part>.<channel>).
std::vector<std::string> channel_names(const ssgi::FileChannels& file) {
  std::vector<std::string> names;
  const bool multipart = file.channels.size() > 1;
  for (std::size_t s = 0; s < file.channels.size(); ++s) {
    const std::string part = s < file.subimage_names.size() ? file.subimage_names[s] : "";
    for (const std::string& c : file.channels[s])
      names.push_back(
          multipart && !part.empty() && c.find('.') == std::string::npos ? part + "." + c : c);
  }
  return names;
}

}  // namespace

std::string resolve_truth_layer(const ssgi::FileChannels& file, const std::string& layer,
                                const std::string& path) {
  const std::vector<std::string> names = channel_names(file);
  auto has_rgb = [&](const std::string& l) {
    for (const char* c : {".R", ".G", ".B"})
      if (std::find(names.begin(), names.end(), l + c) == names.end()) return false;
    return true;
  };
  if (has_rgb(layer)) return layer;
  std::vector<std::string> matches;
  for (const std::string& name : names) {
    const auto dot = name.rfind('.');
    if (dot == std::string::npos) continue;
    const std::string l = name.substr(0, dot);
    const std::string tail = "." + layer;
    if (l.size() > tail.size() && l.compare(l.size() - tail.size(), tail.size(), tail) == 0 &&
        has_rgb(l) && std::find(matches.begin(), matches.end(), l) == matches.end())
      matches.push_back(l);
  }
  if (matches.size() == 1) return matches[0];
  if (matches.empty()) ssgi::throw_input(path, "has no R,G,B layer '" + layer + "' for --truth");
  ssgi::throw_input(path, "--truth '" + layer + "' could be " + matches[0] + " or " + matches[1] +
                              ": give the whole name");
}

}  // namespace ssgi_cli
