// Reading G-buffer sequences from renderer EXRs and writing result frames.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ssgi/camera.h"
#include "ssgi/gbuffer.h"
#include "ssgi/layout.h"
#include "ssgi/sequence.h"

namespace ssgi {

class ColorManagement;

// A set of roles, as bits (1u << Role).
using RoleMask = unsigned;
constexpr RoleMask role_bit(Role role) { return 1u << static_cast<int>(role); }

// An extra view of the shot's scene (--view, --latlong-view): a sequence with the shot's frame
// numbers, or a still (a file name without a frame field) for every frame of a locked-off
// camera.
struct ViewOptions {
  std::string pattern;
  Projection projection = Projection::kPinhole;
};

// What the user said about the input sequence.
struct InputOptions {
  std::string pattern;                         // e.g. "shot.####.exr"
  std::string frames;                          // --frames; empty: the range in the pattern,
                                               // else every frame on disk
  bool skip_missing = false;                   // --skip-missing
  std::string layout;                          // --layout; empty: detect
  std::vector<std::string> channel_overrides;  // --channel ROLE=NAME
  std::string depth_kind;                      // --depth-kind; empty: the preset's
  std::string normal_space;                    // --normal-space; empty: the preset's
  // --normals: "pass" (the file's normal channels), "depth" (from the depth buffer's pixel
  // derivatives), empty or "auto" (the pass when the file has one, else from depth).
  std::string normals;
  CameraOptions camera;  // --fov, --camera
  // --context: the pattern of the whole picture's frames around a region render (the same
  // shot and display window, a data window holding this one's); their passes fill what the
  // data window lacks, so that rays leaving it meet what the whole frame shows. Empty: none.
  std::string context;
  // --view and --latlong-view: read with the options above (the layout, --channel and the
  // conventions; each view's camera its own header's).
  std::vector<ViewOptions> views;
};

struct SequenceInfo;

// An extra view as probed from its first file.
struct ViewInfo {
  std::string pattern;  // as given
  Projection projection = Projection::kPinhole;
  bool still = false;  // one file for every frame
  // Its files as a sequence of their own (its windows, channels and layout; its frames those
  // on disk). For a still, the pattern is the file name itself.
  std::shared_ptr<const SequenceInfo> sequence;
  // The file frame `frame` of the shot reads.
  std::string path_for(int frame) const;
};

// A sequence as found on disk, probed from its first frame.
struct SequenceInfo {
  SequencePattern pattern;
  std::vector<int> frames;          // the frames to write, in order, all present on disk
  std::vector<int> frames_on_disk;  // every frame the pattern matches, ascending
  Box2i display_window;             // of the first frame, absolute EXR coordinates
  Box2i data_window;
  FileChannels channels;  // of the first frame
  Layout layout;          // resolved against the first frame
  double pixel_aspect = 1.0;
  // The first frame's largest chunk in rows: what the file decodes at once (a tile's height, or
  // its compression's block of scanlines), which the reader and the writer's strips hold whole.
  int chunk_rows = 1;
  bool normals_from_depth = false;  // --normals: the reader derives normals from depth
  // --context: the context's frames as probed from their first (its frames those of this
  // sequence); the G-buffers read cover its data window. Null without --context.
  std::shared_ptr<const SequenceInfo> context;
  // --view, --latlong-view: the extra views, in the order given.
  std::vector<ViewInfo> views;

  // The window the G-buffers read cover: the context's data window, else the data window.
  const Box2i& working_window() const { return context ? context->data_window : data_window; }
};

// Resolves frames and probes the first one. Throws Error(kUsage) for a malformed pattern or
// frame list, Error(kIO) naming the file for a missing frame (unless skip_missing, which
// drops it with a warning) or a pattern matching nothing, Error(kInput) when the layout
// cannot be resolved.
SequenceInfo open_sequence(const InputOptions& options);

// Reads the roles in `roles` of one frame and converts them to the library's conventions
// (planar depth with +inf background, unit camera-space normals, direct light with albedo).
// Reads one channel range per subimage. With `color`, the light and albedo passes (albedo,
// direct, emission, beauty's R, G, B) go from the input space to the working space before
// anything else (direct x albedo included); data passes are never transformed. Throws
// Error(kIO) for an unreadable file and Error(kInput) naming it for unusable data (missing
// channel, window or resolution that differs from `sequence`, no camera). With a context
// (sequence.context), the frame is pasted over the context's same frame and covers the
// context's data window; a context frame whose camera differs is Error(kInput) naming it.
GBuffer read_gbuffer(const SequenceInfo& sequence, int frame, RoleMask roles,
                     const InputOptions& options, const ColorManagement* color = nullptr);

// The camera of one frame, from its header alone (or the options' sidecar / field of view).
Camera read_camera(const SequenceInfo& sequence, int frame, const InputOptions& options);

// Sets how many threads OpenImageIO and OpenEXR use (0: their default).
void set_io_threads(int threads);

// A layer of results to write: channels `<prefix><name>.<suffix>` from the planes of `image`
// (an empty name writes bare `<prefix><suffix>`, as the composite's R, G, B, A).
struct OutputLayer {
  std::string name;
  const Image* image = nullptr;
  std::vector<std::string> suffixes;
};

// How to write result frames.
struct WriteOptions {
  std::string compression = "zip";  // OIIO spelling, e.g. "zip", "dwaa:45", "none"
  bool half = false;                // write our channels as half (clamped to +-65504)
  bool passthrough = true;          // copy the input's channels
  std::string layer_prefix;         // --layer-prefix, with its trailing '.'
  std::vector<std::pair<std::string, std::string>> provenance;  // extra string attributes
  bool warn_collisions = true;  // warn when an input channel is renamed to input.<name>
};

// Validates --compression (zip|zips|piz|rle|pxr24|b44|b44a|dwaa[:level]|dwab[:level]|none) and
// returns OIIO's spelling. Throws Error(kUsage) otherwise.
std::string parse_compression(const std::string& spec);

// Validates --layer-prefix (one or more dot-separated names, e.g. "ssgi" or "gi.v2", each of
// printable characters other than space) and returns it with its trailing '.'. Throws
// Error(kUsage) otherwise.
std::string parse_layer_prefix(const std::string& prefix);

// Throws Error(kIO) naming `path` unless the directory `path` would be written into exists.
void check_output_directory(const std::string& path);

// Makes the directory `path` would be written into, with its missing parents (mkdir -p).
// Throws Error(kIO) naming `path` when something that is not a directory is in the way or the
// directory cannot be made.
void make_output_directory(const std::string& path);

// Writes `layers` (covering `frame`'s data window) to `path` with the input's header and,
// when asked, its channels. Written to a temporary file in the same directory, then renamed,
// so a failure never leaves a partial frame. Throws Error(kIO) naming `path` on failure.
void write_frame(const std::string& path, const GBuffer& frame,
                 const std::vector<OutputLayer>& layers, const WriteOptions& options);

// Why the file at `path` cannot stand for the frame a run would write there, or "" when it can:
// it opens as an image, the first and last chunks of every part decode (a truncated file loses
// its last), and its header holds each of `attributes` (name, value) as a string.
std::string why_not_reusable(const std::string& path,
                             const std::vector<std::pair<std::string, std::string>>& attributes);

}  // namespace ssgi
