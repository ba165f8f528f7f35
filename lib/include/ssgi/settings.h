// The settings of a GI run: everything `ssgi run` options control besides input and output.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ssgi {

enum class DenoiseMode { kNone, kPyramid };
enum class TemporalMode { kNone, kEma, kWindow };

// What a ray that leaves the screen (or ends without a hit) brings back.
enum class MissMode {
  // The environment: --env map or --env-color (default black).
  kEnvironment,
  // An estimate from the frame: the environment weighted by the fraction of background
  // pixels, plus the mean light the frame's surfaces reflect weighted by the rest. It assumes
  // the world outside the frame looks, on average, like the world inside it: an interior
  // continues with more walls, an exterior with as much sky as the frame shows.
  kFrame,
  // The surface where the ray leaves the screen continues beyond the edge as its tangent
  // plane; a ray that meets it takes that edge pixel's light, any other miss the environment.
  kExtend,
  // kFrame when the frame's border shows the camera is enclosed (walls, floor and ceiling
  // running alongside the view: an interior), kEnvironment when it does not (a set seen from
  // outside, sky), with a smooth ramp between. See man/ssgi-gi.7, MISSES.
  kAuto,
};

// The seed's denoise pyramid: a joint bilateral filter at 1/4 resolution, then bilateral
// upsampling with a blur at 1/2 and full resolution. Weights are Gaussian in each term.
struct DenoiseSettings {
  int levels = 2;              // downsampling steps: 2 filters at 1/4 resolution, 0 at full
  int radius = 2;              // joint bilateral kernel radius in pixels at the coarsest level
  float sigma_spatial = 1.5f;  // spatial Gaussian, pixels at the coarsest level
  // Depth term: the relative depth difference |z_q - z'_p| / z_p at which the weight is
  // exp(-1/2), where z'_p is p's depth carried to q along p's screen-space depth gradient (so
  // that a slanted plane counts as one surface).
  float sigma_depth = 0.02f;
  // Normal term: weight = max(0, dot(n_p, n_q))^normal_power.
  float normal_power = 32.0f;
  // The edge-aware blur after each bilateral upsampling step (spatial sigma = this radius,
  // in pixels of that level; 0: none).
  int upsample_blur_radius = 1;
};

// Who traces the hemisphere: the slice tracer (a visibility bitmask over screen-space slices,
// the fast default), the exact screen-space march of single rays, or Embree against the depth
// buffer's mesh (ssgi reference). All three follow the same surface model and miss rules.
enum class Tracer { kSlices, kScreenSpace, kReference };

// Each setting's names as the options take them and the output's provenance prints them: one
// table per enum, which parsing, --help and the settings' text all read.
template <typename E>
struct EnumName {
  E value;
  const char* name;
};
inline constexpr EnumName<Tracer> kTracerNames[] = {{Tracer::kSlices, "slices"},
                                                    {Tracer::kScreenSpace, "march"},
                                                    {Tracer::kReference, "reference"}};
inline constexpr EnumName<MissMode> kMissModeNames[] = {{MissMode::kAuto, "auto"},
                                                        {MissMode::kEnvironment, "env"},
                                                        {MissMode::kExtend, "extend"},
                                                        {MissMode::kFrame, "frame"}};
inline constexpr EnumName<DenoiseMode> kDenoiseModeNames[] = {{DenoiseMode::kNone, "none"},
                                                              {DenoiseMode::kPyramid, "pyramid"}};
inline constexpr EnumName<TemporalMode> kTemporalModeNames[] = {
    {TemporalMode::kNone, "none"}, {TemporalMode::kEma, "ema"}, {TemporalMode::kWindow, "window"}};

// `value`'s name in `table` ("?" for a value the table lacks).
template <typename E, std::size_t N>
constexpr const char* enum_name(const EnumName<E> (&table)[N], E value) {
  for (const EnumName<E>& row : table)
    if (row.value == value) return row.name;
  return "?";
}

// The value named `name` in `table`, if any.
template <typename E, std::size_t N>
constexpr std::optional<E> enum_value(const EnumName<E> (&table)[N], std::string_view name) {
  for (const EnumName<E>& row : table)
    if (name == row.name) return row.value;
  return std::nullopt;
}

// The colour spaces of a run, by OpenColorIO names (lib/include/ssgi/color.h applies them).
// Empty means the default each comment gives.
struct ColorSettings {
  std::string config;   // --colorconfig: an OCIO config file; empty: $OCIO, else none
  std::string input;    // --input-colorspace: the light and albedo passes; empty: working
  std::string output;   // --output-colorspace: the colour layers ssgi writes; empty: working
  std::string env;      // --env-colorspace: the environment map; empty: by its file type
  std::string working;  // --working-space: where the GI arithmetic runs; empty: scene_linear
  std::string display;  // --display: the preview's display; empty: the config's default
  std::string view;     // --view: the preview's view; empty: the display's default
};

// The config `settings` names: its `config`, else $OCIO, else "" (none).
std::string color_config_path(const ColorSettings& settings);

// Everything that decides the GI result of a frame.
struct GiSettings {
  Tracer tracer = Tracer::kSlices;
  int rays = 8;        // march and reference: hemisphere rays per pixel and bounce
  int slices = 2;      // slice tracer: slices per trace sample (32 rays each)
  int max_steps = 28;  // samples per ray (march) or per side of a slice at most
  // Data-window pixels per trace sample along each axis (1, 2, 4 or 8): the slice tracer
  // traces from one pixel of each block, and the denoiser's pyramid takes the light from
  // there. 0: the largest scale whose grid is still trace_width samples across (or scale 1),
  // so that a preset costs and looks the same at any resolution.
  int trace_scale = 0;
  int trace_width = 480;
  // Longest ray, in camera-space scene units; 0: until the ray leaves the screen.
  double max_distance = 0;
  // Surface model (lib/src/gi/surface_model.h): a depth pixel is a slab from its depth z to
  // z * (1 + thickness) behind it.
  double thickness = 0.1;
  // A ray starts this fraction of the pixel's depth off the surface along its normal, so that
  // it does not hit its own pixel.
  double start_offset = 0.002;
  int bounces = 8;
  MissMode miss = MissMode::kAuto;
  // The environment: the map (lat-long EXR, empty for none) or else this colour.
  std::string env_map;
  char env_up = 'y';  // the map's up axis in world space: 'y' (OpenEXR) or 'z' (Blender)
  std::array<float, 3> env_color = {0, 0, 0};
  // Gather emission at hits: -1 the preset decides, 0 no, 1 yes.
  int gather_emission = -1;
  DenoiseMode denoise = DenoiseMode::kPyramid;
  DenoiseSettings denoise_settings;
  TemporalMode temporal = TemporalMode::kWindow;
  int temporal_radius = 2;  // window: +-K frames
  // Rays that miss continued in up to this many frames on each side (lib/src/gi/continuation.h;
  // within the temporal window, which reads them anyway); 0: off, kMultiframeWindow: the
  // whole window.
  int multiframe = 0;
  float ema_alpha = 0.1f;  // EMA: weight of the current frame
  std::uint32_t seed = 0;
  ColorSettings color;
};

// GiSettings::multiframe for "as many frames as the temporal window has".
constexpr int kMultiframeWindow = 64;
// GiSettings::multiframe as --multiframe takes it: "off", "on" (kMultiframeWindow), "on:K".
std::string multiframe_text(int multiframe);

// The presets (--preset): `draft` for look development, `default` (what GiSettings{} holds),
// `final` for delivery. Sets the tracing settings of `name` on *settings, leaving the others.
// Throws Error(kUsage) for an unknown name. man/ssgi-gi.7 lists what each sets.
void apply_preset(const std::string& name, GiSettings* settings);

// The names of the presets, in order of cost.
const std::vector<std::string>& preset_names();

// The --miss spelling of a miss mode ("auto", "env", "frame", "extend").
const char* miss_mode_name(MissMode mode);

// --temporal as the options take it: "none", "ema:0.1", "window:2".
std::string temporal_text(const GiSettings& settings);

// Every setting that decides the result, as (name, value) pairs named as the options are,
// for `ssgi info`, --stats and the output's provenance.
std::vector<std::pair<std::string, std::string>> describe_settings(const GiSettings& settings);

}  // namespace ssgi
