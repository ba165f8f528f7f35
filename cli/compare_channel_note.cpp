// The note `ssgi compare` gives when A and B name their channels differently: idiff pairs
// channels by index, so that an ssgi output against a renderer's frame compares unrelated
// channels; the note names the pairs and, where it can, the --channels argument that pairs them
// by name.
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "compare/compare_files.h"
#include "compare_command.h"

namespace ssgi_cli {
namespace {

// How many pairs of differing names the note shows.
constexpr std::size_t kPairsShown = 3;

// The channels of a file's first subimage: as stored (what idiff pairs by index) and as
// --channels names them (a named part's channel without a layer of its own is
// `<part>.<channel>`).
struct FirstSubimage {
  std::vector<std::string> stored, named;
};

std::optional<FirstSubimage> read_first_subimage(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    OIIO::geterror();  // clears the error: the comparison has already reported it
    return std::nullopt;
  }
  FirstSubimage s;
  s.stored = in->spec().channelnames;
  const std::string part = in->spec().get_string_attribute("oiio:subimagename");
  const bool multipart = in->seek_subimage(1, 0);
  for (const std::string& name : s.stored) {
    const bool prefix = multipart && !part.empty() && name.find('.') == std::string::npos;
    s.named.push_back(prefix ? part + "." + name : name);
  }
  return s;
}

// A channel name split at its last '.': its layer (empty for a root channel such as `R`) and
// its suffix.
std::pair<std::string, std::string> split_channel_name(const std::string& channel) {
  const auto dot = channel.rfind('.');
  if (dot == std::string::npos) return {std::string(), channel};
  return {channel.substr(0, dot), channel.substr(dot + 1)};
}

// Suffixes in the order a layer lists them: R, G, B, A, then X, Y, Z, then by name.
bool suffix_before(const std::string& a, const std::string& b) {
  static const std::vector<std::string> kOrder = {"R", "G", "B", "A", "X", "Y", "Z"};
  const auto rank = [](const std::string& s) {
    return std::find(kOrder.begin(), kOrder.end(), s) - kOrder.begin();
  };
  return rank(a) != rank(b) ? rank(a) < rank(b) : a < b;
}

// A file's layers in order of first appearance, each with its suffixes in layer order.
using Layers = std::vector<std::pair<std::string, std::vector<std::string>>>;

Layers layers_of(const std::vector<std::string>& channels) {
  Layers layers;
  for (const std::string& channel : channels) {
    const std::pair<std::string, std::string> parts = split_channel_name(channel);
    const std::string& layer = parts.first;
    auto it = std::find_if(layers.begin(), layers.end(),
                           [&](const auto& entry) { return entry.first == layer; });
    if (it == layers.end()) it = layers.insert(layers.end(), {layer, {}});
    it->second.push_back(parts.second);
  }
  for (auto& [layer, suffixes] : layers) std::sort(suffixes.begin(), suffixes.end(), suffix_before);
  return layers;
}

bool has_layer(const Layers& layers, const std::string& name) {
  return std::any_of(layers.begin(), layers.end(),
                     [&](const auto& entry) { return entry.first == name; });
}

// The --channels items that pair A's layer `a` with B's layer `b` (the same suffixes): the
// layers' names for R, G, B (select_layers() reads a layer name as its R, G, B), else one
// A_CHANNEL=B_CHANNEL item per suffix.
std::vector<std::string> pairing_items(const std::string& a, const std::string& b,
                                       const std::vector<std::string>& suffixes) {
  if (!a.empty() && !b.empty() && suffixes == std::vector<std::string>{"R", "G", "B"})
    return {a + "=" + b};
  std::vector<std::string> items;
  for (const std::string& s : suffixes)
    items.push_back((a.empty() ? s : a + "." + s) + "=" + (b.empty() ? s : b + "." + s));
  return items;
}

// The --channels argument that pairs the layers only A has with those only B has, matched by
// their suffixes; empty unless each such layer of A has exactly one such layer of B with the
// same suffixes and no other layer of A shares them.
std::string derive_channels_argument(const std::vector<std::string>& a_names,
                                     const std::vector<std::string>& b_names) {
  const Layers a = layers_of(a_names), b = layers_of(b_names);
  std::map<std::vector<std::string>, std::vector<std::string>> a_only, b_only;  // by suffixes
  for (const auto& [layer, suffixes] : a)
    if (!has_layer(b, layer)) a_only[suffixes].push_back(layer);
  for (const auto& [layer, suffixes] : b)
    if (!has_layer(a, layer)) b_only[suffixes].push_back(layer);
  std::vector<std::string> items;
  for (const auto& [layer, suffixes] : a) {
    const auto mine = a_only.find(suffixes);
    if (mine == a_only.end() || !b_only.count(suffixes) ||
        std::find(mine->second.begin(), mine->second.end(), layer) == mine->second.end())
      continue;
    const std::vector<std::string>& theirs = b_only.at(suffixes);
    if (mine->second.size() != 1 || theirs.size() != 1) return {};
    for (const std::string& item : pairing_items(layer, theirs[0], suffixes)) items.push_back(item);
  }
  return OIIO::Strutil::join(items, ",");
}

}  // namespace

std::string channel_pairing_note(const std::string& a_path, const std::string& b_path) {
  const std::optional<FirstSubimage> a = read_first_subimage(a_path);
  const std::optional<FirstSubimage> b = read_first_subimage(b_path);
  if (!a || !b) return {};
  std::vector<std::string> pairs;
  for (std::size_t c = 0; c < std::min(a->stored.size(), b->stored.size()); ++c)
    if (a->stored[c] != b->stored[c]) pairs.push_back(a->stored[c] + " with " + b->stored[c]);
  if (pairs.empty()) return {};

  std::string note = "ssgi: warning: A and B name their channels differently; compared by index: ";
  note += OIIO::Strutil::join(
      std::vector<std::string>(pairs.begin(), pairs.begin() + std::min(pairs.size(), kPairsShown)),
      ", ");
  if (pairs.size() > kPairsShown) note += " (" + std::to_string(pairs.size()) + " pairs in all)";
  const std::string argument = derive_channels_argument(a->named, b->named);
  note += "\nssgi: hint: to pair them by name: --channels " +
          (argument.empty() ? std::string("A_NAME=B_NAME[,...] (a channel or an R,G,B layer)")
                            : argument) +
          "\n";
  return note;
}

}  // namespace ssgi_cli
