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
  kDirect,  // direct diffuse light (with or without albedo: see LayoutPreset)
  kEmission,
  kMotion,
  kPosition,
  kBeauty,
  // The renderer's diffuse indirect light (with or without albedo, as its direct pass is): read
  // only from a guide (--guide), never from the shot itself.
  kIndirect,
};
constexpr int kRoleCount = 9;

// "depth", "normal", "albedo", "direct", "emission", "motion", "position", "beauty",
// "indirect".
const char* role_name(Role role);
// Parses a role name as above; returns false when unknown.
bool parse_role(const std::string& name, Role* role);
// Channels a role has, in order: depth Z; normal X Y Z; albedo, direct, emission, indirect
// R G B; motion X Y [Z W] (two or four); position X Y Z; beauty R G B [A].
int role_min_components(Role role);
int role_max_components(Role role);

// How the depth channel encodes distance. The reader converts all of them to planar z.
enum class DepthKind {
  kPlanarZ,    // camera-space z, positive in front (OpenEXR Z, Blender, Arnold Z)
  kRadial,     // distance from the camera centre along the view ray
  kInverseZ,   // 1/z, zero at infinity (Nuke ScanlineRender)
  kNegativeZ,  // -z, negative in front (Fusion)
};
// "planar", "radial", "inverse", "negative".
const char* depth_kind_name(DepthKind kind);
// Parses a name as above; returns false when unknown.
bool parse_depth_kind(const std::string& name, DepthKind* kind);

// The space a normal pass is in. kCamera is the library's camera space (x right, y up, +z
// forward: RenderMan's); kCameraGl the OpenGL one the camera of Maya, Houdini and 3ds Max has
// (x right, y up, looking down -z). kAuto: decided per frame by which space agrees with the
// normals the depth implies.
enum class NormalSpace { kWorld, kCamera, kCameraGl, kAuto };
// "world", "camera", "camera-gl", "auto".
const char* normal_space_name(NormalSpace space);
// Parses a name as above; returns false when unknown.
bool parse_normal_space(const std::string& name, NormalSpace* space);

// How motion vectors are stored, converted by the reader to the library's convention
// (display pixels, +y down, offset from this pixel to the same surface point in the previous
// and in the next frame).
struct MotionConvention {
  // Added to the stored X, Y before scaling: Unreal stores 0.5 for "no motion", so -0.5.
  double offset = 0.0;
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
  // When false, Z and W are not read even if the motion role has them.
  bool zw_current_minus_next = false;
};

// A renderer's channel naming and conventions.
struct LayoutPreset {
  std::string name;      // identifier used by --layout: "blender", "arnold", ...
  std::string renderer;  // human-readable renderer name
  // Per role, candidate sources in order of preference; the first one the file has wins.
  // The same syntax is used by --channel ROLE=NAME:
  //  - a layer name "DiffCol": channels "DiffCol.<c>" for the role's components <c> (R G B,
  //    r g b, X Y Z, ...; see role_min_components), else the same layer under any prefix
  //    ("ViewLayer.DiffCol.R": a Blender view layer); a depth layer may also be a bare
  //    channel of that exact name ("Z");
  //  - a comma-separated list of full channel names "nx,ny,nz", in component order;
  //  - "part:NAME": the subimage (EXR part) named NAME, whose plain channels (R G B, or its
  //    only channel for depth) or "NAME.<c>" channels hold the role.
  // Channels are always looked up by full name: OIIO may reorder channels inside a layer.
  std::vector<std::string> candidates[kRoleCount];
  DepthKind depth_kind = DepthKind::kPlanarZ;
  // World-space normals need the frame's world transform (header, sidecar or a fit to the
  // position pass). kAuto where the renderer's documentation does not say.
  NormalSpace normal_space = NormalSpace::kWorld;
  // Whether the direct and indirect light passes include the albedo (an LPE's radiance) or not
  // (Blender's DiffDir and DiffInd, V-Ray's raw passes).
  bool direct_includes_albedo = false;
  // True for renderers that do not sample emissive surfaces as lights, so emission must be
  // gathered by the rays (ssgi-run(1), --gather-emission).
  bool gather_emission = false;
  // Planar depth, after conversion by depth_kind and in the file's own units, at or beyond
  // which a pixel is background (besides inf, NaN and depth <= 0).
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
  std::vector<std::string> subimage_names;         // oiio:subimagename per subimage
  std::vector<std::vector<std::string>> channels;  // channel names per subimage
  std::map<std::string, std::string> attributes;   // subimage 0's header, as strings
};

// A preset resolved against one file: the channels each role reads from.
struct Layout {
  LayoutPreset preset;                        // conventions (the preset's, after overrides)
  std::vector<ChannelRef> roles[kRoleCount];  // empty: the file does not provide the role
  std::string detected_because;               // why this preset was chosen, for `ssgi info`

  bool has(Role role) const { return !roles[static_cast<int>(role)].empty(); }
  const std::vector<ChannelRef>& channels(Role role) const { return roles[static_cast<int>(role)]; }
};

// All built-in presets, in detection order, followed by "custom" (generic conventions, no
// candidates but a bare R G B [A] beauty: the roles come from --channel overrides).
const std::vector<LayoutPreset>& layout_presets();
// The preset named `name`, or nullptr.
const LayoutPreset* find_layout_preset(const std::string& name);

// Picks the preset for `file` and resolves each role to channels, then applies
// `channel_overrides` ("ROLE=NAME", NAME as in LayoutPreset::candidates).
//
// With `forced_preset` empty the preset is detected. A preset qualifies when the file gives it
// a depth channel (its own candidates or an override) and either its own candidates find the
// depth or the header carries its signature (BlenderMultiChannel, arnold/..., vrayInfo/...,
// nuke/..., unreal/...). Among those, own depth beats signature only, then a signature wins,
// then the most roles resolved, then the earlier preset. When none qualifies but the overrides
// give a depth channel, "custom" is used.
//
// Throws Error(kUsage) on an unknown preset (listing the known ones), an unknown role or a
// malformed or repeated override; Error(kInput) naming `file_name` when an override names
// channels the file lacks, or when no depth channel results.
Layout resolve_layout(const FileChannels& file, const std::string& forced_preset,
                      const std::vector<std::string>& channel_overrides,
                      const std::string& file_name);

}  // namespace ssgi
