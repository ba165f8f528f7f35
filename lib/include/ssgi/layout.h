// Channel layouts: which channels of a renderer's EXR hold which G-buffer role, and the
// renderer's conventions for them. Presets are detected from channel names and metadata.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace ssgi {

enum class Role : int {
  kDepth,
  kNormal,
  kAlbedo,
  kDirect,    // direct diffuse light (with or without albedo: see LayoutPreset)
  kEmission,
  kMotion,
  kPosition,
  kBeauty,
};
constexpr int kRoleCount = 8;

// "depth", "normal", "albedo", "direct", "emission", "motion", "position", "beauty".
const char* role_name(Role role);
// Parses a role name as above; returns false when unknown.
bool parse_role(const std::string& name, Role* role);
// Channels a role has, in order: depth Z; normal X Y Z; albedo, direct, emission R G B;
// motion X Y [Z W]; position X Y Z; beauty R G B [A].
int role_min_components(Role role);
int role_max_components(Role role);

// How the depth channel encodes distance. The reader converts all of them to planar z.
enum class DepthKind {
  kPlanarZ,    // camera-space z, positive in front (OpenEXR Z, Blender, Arnold Z)
  kRadial,     // distance from the camera centre along the view ray
  kInverseZ,   // 1/z, zero at infinity (Nuke ScanlineRender)
  kNegativeZ,  // -z, negative in front (Fusion)
};
const char* depth_kind_name(DepthKind kind);
bool parse_depth_kind(const std::string& name, DepthKind* kind);

enum class NormalSpace { kWorld, kCamera };
const char* normal_space_name(NormalSpace space);

// How motion vectors are stored, converted by the reader to the library's convention
// (display pixels, +y down, offset from this pixel to the same surface point in the previous
// and in the next frame).
struct MotionConvention {
  // Multiplier that turns the stored X, Y into display pixels along x, y; NDC-unit vectors
  // set `in_ndc` and are scaled by the display window's width and height instead.
  double scale = 1.0;
  bool in_ndc = false;
  // True when X, Y point from this frame to the previous one (Blender: previous - current);
  // false when they point to the next frame (current -> next).
  bool xy_to_previous = true;
  // True when the stored y grows upwards (image y is flipped).
  bool y_up = false;
  // True when Z, W hold the other direction, stored as current - next (Blender's Vector.ZW).
  bool zw_current_minus_next = false;
};

// A renderer's channel naming and conventions.
struct LayoutPreset {
  std::string name;      // identifier used by --layout: "blender", "arnold", ...
  std::string renderer;  // human-readable renderer name
  // Per role, candidate sources in order of preference. A candidate is either a layer name
  // ("ViewLayer.DiffCol", "diffuse_albedo", "Z") whose channels are found inside it by
  // component suffix, or a comma-separated list of full channel names. A candidate may start
  // with "part:" to name a subimage (multi-part EXR) whose plain channels hold the role.
  std::vector<std::string> candidates[kRoleCount];
  DepthKind depth_kind = DepthKind::kPlanarZ;
  NormalSpace normal_space = NormalSpace::kWorld;
  bool direct_includes_albedo = false;
  // True for renderers that do not sample emissive surfaces as lights, so emission must be
  // gathered by the march (see DESIGN.md, "Radiance gathered").
  bool gather_emission = false;
  // Depth at or beyond this is background (besides inf and NaN).
  double background_depth = 1e9;
  MotionConvention motion;
  // Where the conventions above are documented (a URL or a manual section).
  std::string reference;
};

// One channel in a file: the subimage (EXR part) it is in and its full name there.
struct ChannelRef {
  int subimage = 0;
  std::string name;
};

// What a file offers, as the layout resolver sees it.
struct FileChannels {
  std::vector<std::string> subimage_names;            // oiio:subimagename per subimage
  std::vector<std::vector<std::string>> channels;     // channel names per subimage
  std::map<std::string, std::string> attributes;      // subimage 0's header, as strings
};

// A preset resolved against one file: the channels each role reads from.
struct Layout {
  LayoutPreset preset;                   // conventions (the preset's, after overrides)
  std::vector<ChannelRef> roles[kRoleCount];  // empty: the file does not provide the role
  std::string detected_because;          // why this preset was chosen, for `ssgi info`

  bool has(Role role) const { return !roles[static_cast<int>(role)].empty(); }
  const std::vector<ChannelRef>& channels(Role role) const {
    return roles[static_cast<int>(role)];
  }
};

// All built-in presets, in detection order.
const std::vector<LayoutPreset>& layout_presets();
// The preset named `name`, or nullptr.
const LayoutPreset* find_layout_preset(const std::string& name);

// Picks the preset for `file` (detected, or `forced_preset` when not empty), resolves each role
// to channels, then applies `channel_overrides` ("ROLE=NAME": a layer name or a comma list of
// full channel names, see LayoutPreset::candidates). Throws Error(kUsage) on an unknown preset
// or role or a malformed override, Error(kInput) naming `file_name` when an override names
// channels the file lacks or no preset matches and no overrides give a depth channel.
Layout resolve_layout(const FileChannels& file, const std::string& forced_preset,
                      const std::vector<std::string>& channel_overrides,
                      const std::string& file_name);

}  // namespace ssgi
