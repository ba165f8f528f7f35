// The settings of a GI run: everything `ssgi run` options control besides input and output.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace ssgi {

enum class DenoiseMode { kNone, kPyramid };  // --denoise: none, or the pyramid (DenoiseSettings)
// --temporal: none, the seed's exponential moving average, or the symmetric window of frames.
enum class TemporalMode { kNone, kEma, kWindow };

// What a ray that leaves the screen (or ends without a hit) brings back.
enum class MissMode {
  // The environment: --env map or --env-color (default black).
  kEnvironment,
  // An estimate from the frame, whose outside is taken to look like its inside: the environment
  // over the share of background pixels, the mean light the surfaces reflect over the rest.
  kFrame,
  // The surface where the ray leaves the screen continues beyond the edge as its tangent
  // plane; a ray that meets it takes that edge pixel's light, any other miss the environment.
  kExtend,
  // kFrame where the frame's border shows the camera enclosed (walls, floor and ceiling along
  // the view), kEnvironment where it does not (sky), a ramp between (man ssgi-gi, MISSES).
  kAuto,
};

// The seed's denoise pyramid: a joint bilateral filter at 1/4 resolution, then bilateral
// upsampling with a blur at 1/2 and full resolution. Weights are Gaussian in each term.
struct DenoiseSettings {
  int levels = 2;              // downsampling steps: 2 filters at 1/4 resolution, 0 at full
  int radius = 2;              // joint bilateral kernel radius in pixels at the coarsest level
  float sigma_spatial = 1.5f;  // spatial Gaussian, pixels at the coarsest level
  // Depth term: the relative difference |z_q - z'_p| / z_p weighted exp(-1/2), z'_p being p's
  // depth carried to q along its screen-space gradient (a slanted plane is one surface).
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

// The colour spaces of a run, by OpenColorIO names; empty means the default each comment gives.
struct ColorSettings {
  std::string config;   // --colorconfig: an OCIO config file; empty: $OCIO, else none
  std::string input;    // --input-colorspace: the light and albedo passes; empty: working
  std::string output;   // --output-colorspace: the colour layers ssgi writes; empty: working
  std::string env;      // --env-colorspace: the environment map; empty: by its file type
  std::string working;  // --working-space: where the GI arithmetic runs; empty: scene_linear
  std::string display;  // --display: the preview's display; empty: the config's default
  std::string view;     // --view: the preview's view; empty: the display's default
};

// Everything that decides the GI result of a frame.
struct GiSettings {
  Tracer tracer = Tracer::kSlices;
  int rays = 8;        // march and reference: hemisphere rays per pixel and bounce
  int slices = 2;      // slice tracer: slices per trace sample (32 rays each)
  int max_steps = 28;  // samples per ray (march) or per side of a slice at most
  // Data-window pixels per slice-tracer sample along each axis (1, 2, 4 or 8); 0: the largest
  // whose grid is still trace_width samples across (or 1), so that a preset costs and looks the
  // same at any resolution.
  int trace_scale = 0;
  int trace_width = 480;
  // Longest ray, in camera-space scene units; 0: until the ray leaves the screen.
  double max_distance = 0;
  // Surface model: a depth pixel is a slab from its depth z to z * (1 + thickness) behind it.
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
  // Missed rays continued in up to this many frames each side, within the temporal window
  // (man ssgi-gi); 0: off, kMultiframeWindow: the whole window.
  int multiframe = 0;
  float ema_alpha = 0.1f;  // EMA: weight of the current frame
  std::uint32_t seed = 0;
  ColorSettings color;
};

// GiSettings::multiframe for "as many frames as the temporal window has".
constexpr int kMultiframeWindow = 64;

// The presets (--preset): `draft` for look development, `default` (what GiSettings{} holds),
// `final` for delivery. Sets the tracing settings of `name` on *settings, leaving the others.
// Throws Error(kUsage) for an unknown name. man/ssgi-gi.7 lists what each sets.
void apply_preset(const std::string& name, GiSettings* settings);

}  // namespace ssgi
