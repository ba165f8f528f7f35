// Channel layout presets, their detection from channel names and header attributes, and
// --channel overrides.
#include "io/layout.h"

#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <cstddef>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "io/layout_presets.h"
#include "throw.h"

namespace ssgi {
namespace {

namespace Strutil = OIIO::Strutil;

constexpr const char* kRoleNames[kRoleCount] = {
    "depth", "normal", "albedo", "direct", "emission", "motion", "position", "beauty", "indirect"};

constexpr const char* kPartPrefix = "part:";

// Component names a role's channels may carry, tried in order; a role resolves with the first
// set that has all of its required components. Renderers differ: Blender writes X Y Z for
// vectors, Arnold R G B or X Y Z by AOV type, RenderMan lower case, Nuke u v for motion and
// red green blue in its own layer notation.
const std::vector<std::vector<std::string>>& component_sets(Role role) {
  static const std::vector<std::vector<std::string>> kDepth = {{"Z"}, {"V"}, {"R"}, {"z"}, {"r"}};
  static const std::vector<std::vector<std::string>> kVector = {
      {"X", "Y", "Z"}, {"x", "y", "z"}, {"R", "G", "B"}, {"r", "g", "b"}, {"red", "green", "blue"}};
  static const std::vector<std::vector<std::string>> kColour = {
      {"R", "G", "B"}, {"r", "g", "b"}, {"red", "green", "blue"}};
  static const std::vector<std::vector<std::string>> kMotion = {
      {"X", "Y", "Z", "W"}, {"x", "y", "z", "w"}, {"R", "G", "B", "A"},
      {"r", "g", "b", "a"}, {"u", "v"},           {"red", "green", "blue", "alpha"}};
  static const std::vector<std::vector<std::string>> kBeauty = {
      {"R", "G", "B", "A"}, {"r", "g", "b", "a"}, {"red", "green", "blue", "alpha"}};
  switch (role) {
    case Role::kDepth:
      return kDepth;
    case Role::kNormal:
    case Role::kPosition:
      return kVector;
    case Role::kMotion:
      return kMotion;
    case Role::kBeauty:
      return kBeauty;
    case Role::kAlbedo:
    case Role::kDirect:
    case Role::kEmission:
    case Role::kIndirect:
      break;
  }
  return kColour;
}

// Channel counts a role accepts, largest first: optional components come as a whole (motion's
// Z W are the second vector, read as a pair or not at all).
std::vector<int> allowed_counts(Role role) {
  switch (role) {
    case Role::kMotion:
      return {4, 2};
    case Role::kBeauty:
      return {4, 3};
    default:
      return {role_min_components(role)};
  }
}

// A header test that identifies a renderer.
struct Signature {
  enum class Kind { kKey, kKeyPrefix, kSoftware };
  Kind kind;
  std::string text;  // the key, the key prefix, or a substring of the Software attribute
};

struct PresetEntry {
  LayoutPreset preset;
  std::vector<Signature> signature;
};

// A row of the table that says what it does not know is refused: a misspelt key must not go
// unnoticed as a default.
void check_keys(const nlohmann::json& object, std::initializer_list<const char*> known,
                const std::string& where) {
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return key == k; }))
      throw Error(ErrorKind::kInternal, "", "layout presets: " + where + ": unknown key " + key);
  }
}

// The preset table: lib/src/io/layout_presets.json, a row per renderer, compiled in. Defaults
// are LayoutPreset's for what a row leaves out.
std::vector<PresetEntry> build_presets() {
  const nlohmann::json json = nlohmann::json::parse(detail::kLayoutPresetsJson);
  std::vector<PresetEntry> table;
  for (const nlohmann::json& row : json.at("presets")) {
    PresetEntry e;
    LayoutPreset& p = e.preset;
    p.name = row.at("name").get<std::string>();
    check_keys(row,
               {"name", "renderer", "roles", "depth_kind", "normals", "direct_includes_albedo",
                "gather_emission", "background_depth", "motion", "reference", "signature", "notes"},
               p.name);
    p.renderer = row.at("renderer").get<std::string>();
    for (const auto& [name, candidates] : row.at("roles").items()) {
      Role role;
      if (!parse_role(name, &role))
        throw Error(ErrorKind::kInternal, "", "layout presets: " + p.name + ": no role " + name);
      p.candidates[static_cast<int>(role)] = candidates.get<std::vector<std::string>>();
    }
    if (row.contains("depth_kind") &&
        !parse_depth_kind(row["depth_kind"].get<std::string>(), &p.depth_kind))
      throw Error(ErrorKind::kInternal, "", "layout presets: " + p.name + ": bad depth_kind");
    if (row.contains("normals")) {
      if (!parse_normal_space(row["normals"].get<std::string>(), &p.normal_space))
        throw Error(ErrorKind::kInternal, "", "layout presets: " + p.name + ": bad normals");
    }
    p.direct_includes_albedo = row.value("direct_includes_albedo", p.direct_includes_albedo);
    p.gather_emission = row.value("gather_emission", p.gather_emission);
    p.background_depth = row.value("background_depth", p.background_depth);
    if (row.contains("motion")) {
      const nlohmann::json& m = row["motion"];
      check_keys(m,
                 {"offset", "scale", "in_ndc", "xy_to_previous", "y_up", "zw_current_minus_next"},
                 p.name + " motion");
      p.motion.offset = m.value("offset", p.motion.offset);
      p.motion.scale = m.value("scale", p.motion.scale);
      p.motion.in_ndc = m.value("in_ndc", p.motion.in_ndc);
      p.motion.xy_to_previous = m.value("xy_to_previous", p.motion.xy_to_previous);
      p.motion.y_up = m.value("y_up", p.motion.y_up);
      p.motion.zw_current_minus_next =
          m.value("zw_current_minus_next", p.motion.zw_current_minus_next);
    }
    p.reference = row.at("reference").get<std::string>();
    for (const nlohmann::json& test : row.value("signature", nlohmann::json::array())) {
      check_keys(test, {"key", "key_prefix", "software"}, p.name + " signature");
      if (test.contains("key"))
        e.signature.push_back({Signature::Kind::kKey, test["key"].get<std::string>()});
      else if (test.contains("key_prefix"))
        e.signature.push_back({Signature::Kind::kKeyPrefix, test["key_prefix"].get<std::string>()});
      else if (test.contains("software"))
        e.signature.push_back({Signature::Kind::kSoftware, test["software"].get<std::string>()});
    }
    table.push_back(std::move(e));
  }
  return table;
}

const std::vector<PresetEntry>& preset_table() {
  static const std::vector<PresetEntry> table = build_presets();
  return table;
}

std::string known_preset_names() {
  std::string names;
  for (const PresetEntry& e : preset_table()) {
    if (!names.empty()) names += ", ";
    names += e.preset.name;
  }
  return names;
}

// `s` without the spaces and tabs around it.
std::string trimmed(const std::string& s) { return std::string(Strutil::strip(s, " \t")); }

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = s.find(',', start);
    parts.push_back(trimmed(s.substr(start, comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return parts;
}

// Where each channel name is, for lookups by full name.
class ChannelIndex {
 public:
  explicit ChannelIndex(const FileChannels& file) : file_(file) {
    per_subimage_.resize(file.channels.size());
    for (std::size_t s = 0; s < file.channels.size(); ++s)
      for (const std::string& name : file.channels[s]) per_subimage_[s].insert(name);
  }

  int subimage_count() const { return static_cast<int>(per_subimage_.size()); }
  bool has(int subimage, const std::string& name) const {
    return per_subimage_[subimage].count(name) > 0;
  }
  // The first subimage holding `name`, or -1.
  int find(const std::string& name) const {
    for (int s = 0; s < subimage_count(); ++s)
      if (has(s, name)) return s;
    return -1;
  }
  // The first subimage named `part`, or -1.
  int find_part(const std::string& part) const {
    for (std::size_t s = 0; s < file_.subimage_names.size() && s < per_subimage_.size(); ++s)
      if (file_.subimage_names[s] == part) return static_cast<int>(s);
    return -1;
  }
  const std::vector<std::string>& channels(int subimage) const { return file_.channels[subimage]; }

 private:
  const FileChannels& file_;
  std::vector<std::set<std::string>> per_subimage_;
};

std::string layer_channel(const std::string& layer, const std::string& component) {
  return layer.empty() ? component : layer + "." + component;
}

// Channels "<layer>.<c>" for the role's components, all in one subimage (`only_subimage`, or
// the first that has them when negative).
bool match_layer(const ChannelIndex& index, Role role, const std::string& layer, int only_subimage,
                 std::vector<ChannelRef>* out) {
  for (const std::vector<std::string>& set : component_sets(role)) {
    for (int count : allowed_counts(role)) {
      if (count > static_cast<int>(set.size())) continue;
      const int first = only_subimage >= 0 ? only_subimage : 0;
      const int last = only_subimage >= 0 ? only_subimage + 1 : index.subimage_count();
      for (int s = first; s < last; ++s) {
        bool all = true;
        for (int c = 0; c < count && all; ++c) all = index.has(s, layer_channel(layer, set[c]));
        if (!all) continue;
        out->clear();
        for (int c = 0; c < count; ++c) out->push_back({s, layer_channel(layer, set[c])});
        return true;
      }
    }
  }
  // A one-channel role also takes a layer of a single channel, whatever its component is
  // called (`zdist.Y`).
  if (role_max_components(role) == 1 && !layer.empty()) {
    const std::string head = layer + ".";
    const int first = only_subimage >= 0 ? only_subimage : 0;
    const int last = only_subimage >= 0 ? only_subimage + 1 : index.subimage_count();
    for (int s = first; s < last; ++s) {
      std::vector<std::string> found;
      for (const std::string& name : index.channels(s))
        if (Strutil::starts_with(name, head) && name.find('.', head.size()) == std::string::npos)
          found.push_back(name);
      if (found.size() != 1) continue;
      *out = {{s, found[0]}};
      return true;
    }
  }
  return false;
}

// Prefixes P (ending in '.') under which channels "P<layer>.<c>" exist, in file order with
// `preferred` first: Blender's view layers ("ViewLayer.", "Background.").
std::vector<std::string> layer_prefixes(const ChannelIndex& index, const std::string& layer,
                                        const std::string& preferred) {
  std::vector<std::string> prefixes;
  const std::string needle = "." + layer + ".";
  for (int s = 0; s < index.subimage_count(); ++s) {
    for (const std::string& name : index.channels(s)) {
      if (name.size() <= needle.size()) continue;
      const std::size_t at = name.rfind(needle);
      if (at == std::string::npos || at + needle.size() >= name.size()) continue;
      // Only the last dot-separated field may follow: it is the component.
      if (name.find('.', at + needle.size()) != std::string::npos) continue;
      const std::string prefix = name.substr(0, at + 1);
      if (std::find(prefixes.begin(), prefixes.end(), prefix) == prefixes.end())
        prefixes.push_back(prefix);
    }
  }
  auto it = std::find(prefixes.begin(), prefixes.end(), preferred);
  if (it != prefixes.end()) std::rotate(prefixes.begin(), it, it + 1);
  return prefixes;
}

struct Match {
  std::vector<ChannelRef> channels;
  std::string prefix;  // the layer prefix a suffix match used, "" otherwise
};

bool match_part(const ChannelIndex& index, Role role, const std::string& part, Match* m) {
  const int s = index.find_part(part);
  if (s < 0) return false;
  if (role_max_components(role) == 1 && index.channels(s).size() == 1) {
    m->channels = {{s, index.channels(s)[0]}};
    return true;
  }
  if (match_layer(index, role, "", s, &m->channels)) return true;
  if (match_layer(index, role, part, s, &m->channels)) return true;
  if (role == Role::kDepth && index.has(s, part)) {
    m->channels = {{s, part}};
    return true;
  }
  return false;
}

bool match_list(const ChannelIndex& index, Role role, const std::string& list, Match* m) {
  const std::vector<std::string> names = split_commas(list);
  const std::vector<int> counts = allowed_counts(role);
  if (std::find(counts.begin(), counts.end(), static_cast<int>(names.size())) == counts.end())
    return false;
  m->channels.clear();
  for (const std::string& name : names) {
    const int s = index.find(name);
    if (s < 0) return false;
    m->channels.push_back({s, name});
  }
  return true;
}

// Resolves one candidate (see LayoutPreset::candidates) for `role`.
bool match_candidate(const ChannelIndex& index, Role role, const std::string& candidate,
                     const std::string& preferred_prefix, Match* m) {
  m->prefix.clear();
  if (Strutil::starts_with(candidate, kPartPrefix))
    return match_part(index, role, candidate.substr(std::string(kPartPrefix).size()), m);
  if (candidate.find(',') != std::string::npos) return match_list(index, role, candidate, m);
  if (match_layer(index, role, candidate, -1, &m->channels)) return true;
  // A bare channel only by its exact name: "Z" must not match "ViewLayer.Depth.Z".
  if (role == Role::kDepth) {
    const int s = index.find(candidate);
    if (s >= 0) {
      m->channels = {{s, candidate}};
      return true;
    }
  }
  for (const std::string& prefix : layer_prefixes(index, candidate, preferred_prefix)) {
    if (match_layer(index, role, prefix + candidate, -1, &m->channels)) {
      m->prefix = prefix;
      return true;
    }
  }
  return false;
}

// A preset's candidates resolved against one file. Depth goes first so that the view layer it
// is found in is preferred for the other roles.
struct Resolution {
  std::vector<ChannelRef> roles[kRoleCount];
  std::string prefix;
  int resolved = 0;
};

Resolution resolve_candidates(const LayoutPreset& preset, const ChannelIndex& index) {
  Resolution r;
  for (int i = 0; i < kRoleCount; ++i) {
    const Role role = static_cast<Role>(i);
    for (const std::string& candidate : preset.candidates[i]) {
      Match m;
      if (!match_candidate(index, role, candidate, r.prefix, &m)) continue;
      r.roles[i] = std::move(m.channels);
      if (role == Role::kDepth) r.prefix = m.prefix;
      ++r.resolved;
      break;
    }
  }
  return r;
}

// The header evidence for `entry`, e.g. "header attribute arnold/version"; empty if none.
std::string signature_evidence(const PresetEntry& entry, const FileChannels& file) {
  for (const Signature& sig : entry.signature) {
    for (const auto& [key, value] : file.attributes) {
      switch (sig.kind) {
        case Signature::Kind::kKey:
          if (key == sig.text) return "header attribute " + key;
          break;
        case Signature::Kind::kKeyPrefix:
          if (Strutil::starts_with(key, sig.text)) return "header attribute " + key;
          break;
        case Signature::Kind::kSoftware:
          if (key == "Software" && value.find(sig.text) != std::string::npos)
            return "header attribute Software \"" + value + "\"";
          break;
      }
    }
  }
  return {};
}

struct Override {
  Role role;
  std::string text;  // "ROLE=NAME" as given
  std::string name;  // NAME
};

std::string role_list() {
  std::string list;
  for (const char* name : kRoleNames) {
    if (!list.empty()) list += ", ";
    list += name;
  }
  return list;
}

// Parses and checks the overrides' syntax, before any file is looked at.
std::vector<Override> parse_overrides(const std::vector<std::string>& texts) {
  std::vector<Override> overrides;
  bool seen[kRoleCount] = {};
  for (const std::string& text : texts) {
    const std::size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
      throw_usage("--channel '" + text + "': expected ROLE=NAME, e.g. albedo=DiffCol");
    Override o;
    o.text = text;
    o.name = text.substr(eq + 1);
    const std::string role = trimmed(text.substr(0, eq));
    if (!parse_role(role, &o.role))
      throw_usage("--channel '" + text + "': unknown role '" + role + "' (roles: " + role_list() +
                  ")");
    const int r = static_cast<int>(o.role);
    if (seen[r]) throw_usage("--channel: role " + role + " given twice");
    seen[r] = true;
    if (o.name.find(',') != std::string::npos) {
      const std::vector<std::string> names = split_commas(o.name);
      for (const std::string& n : names)
        if (n.empty()) throw_usage("--channel '" + text + "': empty channel name in the list");
      const std::vector<int> counts = allowed_counts(o.role);
      if (std::find(counts.begin(), counts.end(), static_cast<int>(names.size())) == counts.end()) {
        std::string wanted = std::to_string(counts.back());
        if (counts.size() > 1)
          wanted = std::to_string(counts.back()) + " or " + std::to_string(counts.front());
        throw_usage("--channel '" + text + "': " + role + " takes " + wanted + " channels, got " +
                    std::to_string(names.size()));
      }
    } else if (Strutil::starts_with(o.name, kPartPrefix) &&
               o.name.size() == std::string(kPartPrefix).size()) {
      throw_usage("--channel '" + text + "': part: needs a part name");
    }
    overrides.push_back(std::move(o));
  }
  return overrides;
}

// What an override looked for, for the error message.
std::string override_search(const Override& o) {
  if (Strutil::starts_with(o.name, kPartPrefix))
    return "a part named " + o.name.substr(std::string(kPartPrefix).size());
  if (o.name.find(',') != std::string::npos) return "channels " + o.name;
  const std::vector<std::string>& first = component_sets(o.role).front();
  std::string comps;
  for (int c = 0; c < role_min_components(o.role); ++c) comps += (c ? "," : "") + first[c];
  std::string what = o.name + ".{" + comps + "} or *." + o.name + ".{" + comps + "}";
  if (o.role == Role::kDepth) what += " or a channel named " + o.name;
  return what;
}

// "ViewLayer.Normal.{X,Y,Z}" for channels sharing a layer, else the names joined by commas;
// channels of a named part are shown as "part/channel" or "part/{R,G,B}".
std::string describe_channels(const std::vector<ChannelRef>& refs, const FileChannels& file) {
  auto part_of = [&](const ChannelRef& c) -> std::string {
    if (c.subimage < static_cast<int>(file.subimage_names.size()) && file.channels.size() > 1 &&
        !file.subimage_names[c.subimage].empty())
      return file.subimage_names[c.subimage] + "/";
    return {};
  };
  std::string out = part_of(refs.front());
  const std::size_t dot = refs.front().name.rfind('.');
  bool common = refs.size() > 1 && dot != std::string::npos;
  const std::string layer = common ? refs.front().name.substr(0, dot + 1) : std::string();
  for (const ChannelRef& c : refs)
    common = common && Strutil::starts_with(c.name, layer) &&
             c.name.find('.', layer.size()) == std::string::npos;
  if (common) {
    out += layer + "{";
    for (std::size_t i = 0; i < refs.size(); ++i)
      out += (i ? "," : "") + refs[i].name.substr(layer.size());
    return out + "}";
  }
  const bool in_part = !out.empty() && refs.size() > 1;
  if (in_part) out += "{";
  for (std::size_t i = 0; i < refs.size(); ++i) out += (i ? "," : "") + refs[i].name;
  return in_part ? out + "}" : out;
}

std::string describe_roles(const Layout& layout, const FileChannels& file) {
  std::string out;
  for (int i = 0; i < kRoleCount; ++i) {
    if (layout.roles[i].empty()) continue;
    if (!out.empty()) out += ", ";
    out += std::string(kRoleNames[i]) + " " + describe_channels(layout.roles[i], file);
  }
  return out.empty() ? "no channels" : "channels " + out;
}

void apply_overrides(const std::vector<Override>& overrides, const ChannelIndex& index,
                     const std::string& preferred_prefix, const std::string& file_name,
                     Layout* layout) {
  for (const Override& o : overrides) {
    Match m;
    if (!match_candidate(index, o.role, o.name, preferred_prefix, &m)) {
      // The shot need not have the indirect light a guide's --channel names: the guide is
      // refused for lacking it (io/guide.h), the shot never reads its own.
      if (o.role == Role::kIndirect) continue;
      throw_input(file_name, "--channel " + o.text + ": the file has no " + override_search(o));
    }
    layout->roles[static_cast<int>(o.role)] = std::move(m.channels);
  }
}

std::string tried_depth_candidates() {
  std::string tried;
  for (const PresetEntry& e : preset_table()) {
    for (const std::string& c : e.preset.candidates[static_cast<int>(Role::kDepth)]) {
      if (!tried.empty()) tried += ", ";
      tried += c;
    }
  }
  return tried;
}

}  // namespace

const char* role_name(Role role) { return kRoleNames[static_cast<int>(role)]; }

bool parse_role(const std::string& name, Role* role) {
  for (int i = 0; i < kRoleCount; ++i) {
    if (name == kRoleNames[i]) {
      *role = static_cast<Role>(i);
      return true;
    }
  }
  return false;
}

int role_min_components(Role role) {
  switch (role) {
    case Role::kDepth:
      return 1;
    case Role::kMotion:
      return 2;
    default:
      return 3;
  }
}

int role_max_components(Role role) {
  switch (role) {
    case Role::kDepth:
      return 1;
    case Role::kMotion:
    case Role::kBeauty:
      return 4;
    default:
      return 3;
  }
}

const char* depth_kind_name(DepthKind kind) {
  switch (kind) {
    case DepthKind::kPlanarZ:
      return "planar";
    case DepthKind::kRadial:
      return "radial";
    case DepthKind::kInverseZ:
      return "inverse";
    case DepthKind::kNegativeZ:
      return "negative";
  }
  return "planar";
}

bool parse_depth_kind(const std::string& name, DepthKind* kind) {
  for (DepthKind k :
       {DepthKind::kPlanarZ, DepthKind::kRadial, DepthKind::kInverseZ, DepthKind::kNegativeZ}) {
    if (name == depth_kind_name(k)) {
      *kind = k;
      return true;
    }
  }
  return false;
}

const char* normal_space_name(NormalSpace space) {
  switch (space) {
    case NormalSpace::kWorld:
      return "world";
    case NormalSpace::kCamera:
      return "camera";
    case NormalSpace::kCameraGl:
      return "camera-gl";
    case NormalSpace::kAuto:
      break;
  }
  return "auto";
}

bool parse_normal_space(const std::string& name, NormalSpace* space) {
  for (NormalSpace s :
       {NormalSpace::kWorld, NormalSpace::kCamera, NormalSpace::kCameraGl, NormalSpace::kAuto}) {
    if (name == normal_space_name(s)) {
      *space = s;
      return true;
    }
  }
  return false;
}

const std::vector<LayoutPreset>& layout_presets() {
  static const std::vector<LayoutPreset> presets = [] {
    std::vector<LayoutPreset> v;
    for (const PresetEntry& e : preset_table()) v.push_back(e.preset);
    return v;
  }();
  return presets;
}

const LayoutPreset* find_layout_preset(const std::string& name) {
  for (const LayoutPreset& p : layout_presets())
    if (p.name == name) return &p;
  return nullptr;
}

Layout resolve_layout(const FileChannels& file, const std::string& forced_preset,
                      const std::vector<std::string>& channel_overrides,
                      const std::string& file_name) {
  const std::vector<PresetEntry>& table = preset_table();
  const PresetEntry* forced = nullptr;
  if (!forced_preset.empty()) {
    for (const PresetEntry& e : table)
      if (e.preset.name == forced_preset) forced = &e;
    if (!forced)
      throw_usage("unknown --layout '" + forced_preset + "' (known: " + known_preset_names() + ")");
  }
  const std::vector<Override> overrides = parse_overrides(channel_overrides);
  const ChannelIndex index(file);
  // Every override must name channels the file has, whichever preset is chosen.
  for (const Override& o : overrides) {
    Match m;
    if (!match_candidate(index, o.role, o.name, "", &m))
      throw_input(file_name, "--channel " + o.text + ": the file has no " + override_search(o));
  }
  const bool override_depth = std::any_of(overrides.begin(), overrides.end(),
                                          [](const Override& o) { return o.role == Role::kDepth; });

  const PresetEntry* chosen = forced;
  Resolution chosen_resolution;
  std::string evidence;
  if (forced) {
    chosen_resolution = resolve_candidates(forced->preset, index);
    evidence = "--layout " + forced->preset.name;
  } else {
    // Rank: own depth, then a signature, then roles resolved; the table order breaks ties.
    int best_score = -1;
    for (const PresetEntry& e : table) {
      if (e.preset.name == "custom") continue;
      Resolution r = resolve_candidates(e.preset, index);
      const bool own_depth = !r.roles[static_cast<int>(Role::kDepth)].empty();
      const std::string sig = signature_evidence(e, file);
      if (!own_depth && !(override_depth && !sig.empty())) continue;
      const int score = (own_depth ? 1000 : 0) + (sig.empty() ? 0 : 100) + r.resolved;
      if (score > best_score) {
        best_score = score;
        chosen = &e;
        chosen_resolution = std::move(r);
        evidence = sig;
      }
    }
    if (!chosen && override_depth) {
      for (const PresetEntry& e : table)
        if (e.preset.name == "custom") chosen = &e;
      chosen_resolution = resolve_candidates(chosen->preset, index);
      evidence = "no preset matched";
    }
    if (!chosen)
      throw_input(file_name,
                  "no channel layout preset matches: no depth channel (looked for " +
                      tried_depth_candidates() +
                      "); name it with --channel depth=NAME or pick a preset with --layout " +
                      known_preset_names());
  }

  Layout layout;
  layout.preset = chosen->preset;
  for (int i = 0; i < kRoleCount; ++i) layout.roles[i] = chosen_resolution.roles[i];
  apply_overrides(overrides, index, chosen_resolution.prefix, file_name, &layout);
  // A second motion vector that the conventions say not to read is not read at all.
  std::vector<ChannelRef>& motion = layout.roles[static_cast<int>(Role::kMotion)];
  if (motion.size() == 4 && !layout.preset.motion.zw_current_minus_next) motion.resize(2);
  if (!layout.has(Role::kDepth)) {
    const auto& tried = chosen->preset.candidates[static_cast<int>(Role::kDepth)];
    std::string looked;
    for (const std::string& c : tried) looked += (looked.empty() ? "" : ", ") + c;
    throw_input(file_name, "--layout " + chosen->preset.name + ": no depth channel" +
                               (looked.empty() ? std::string() : " (looked for " + looked + ")") +
                               "; name it with --channel depth=NAME");
  }

  layout.detected_because = evidence;
  if (!layout.detected_because.empty()) layout.detected_because += "; ";
  layout.detected_because += describe_roles(layout, file);
  for (const Override& o : overrides) layout.detected_because += "; --channel " + o.text;
  return layout;
}

}  // namespace ssgi
