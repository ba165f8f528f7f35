// A run's input and output: what it reads, how it writes, and what became of each frame.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "ssgi/camera.h"
#include "ssgi/error.h"
#include "ssgi/gbuffer.h"

namespace ssgi {

// An extra view of the shot's scene (--view, --latlong-view): a sequence with the shot's frame
// numbers, or a still (no frame field) for every frame of a locked-off camera.
struct ViewOptions {
  std::string pattern;
  Projection projection = Projection::kPinhole;
};

// What the user said about the input sequence: the options of `ssgi run` (man ssgi-run).
struct InputOptions {
  std::string pattern;        // e.g. "shot.####.exr"
  std::string frames;         // --frames; empty: the range in the pattern, else every frame on disk
  bool skip_missing = false;  // --skip-missing
  std::string layout;         // --layout; empty: detect
  std::vector<std::string> channel_overrides;  // --channel ROLE=NAME
  std::string depth_kind;                      // --depth-kind; empty: the preset's
  std::string normal_space;                    // --normal-space; empty: the preset's
  std::string normals;   // --normals: "pass", "depth" (from its derivatives); empty: "auto"
  CameraOptions camera;  // --fov, --camera
  // --context: the whole frames around a region render, whose passes fill what its data window
  // lacks, so that rays leaving it meet what the whole frame shows. Empty: none.
  std::string context;
  std::vector<ViewOptions> views;  // --view, --latlong-view: read as the input is
  // --guide: a few-sample render of the shot with the renderer's diffuse indirect light, read as
  // the input is; empty: none.
  std::string guide;
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

// What a guide (--guide) did to a frame's light, over its trace samples on surfaces.
struct GuideStats {
  bool used = false;
  double known_share = 0;     // the share of the samples the guide gives the light of
  double residual_share = 0;  // the share of the light the guide's residual brought (< 0: took)
  double detail_kept = 0;     // the mean weight of the residual's own detail (1: as it is)
};

// What became of one frame.
struct FrameReport {
  int frame = 0;
  std::string input, output;
  bool ok = false;
  bool skipped = false;                         // ok: the output was already there (skip_existing)
  ErrorKind error_kind = ErrorKind::kInternal;  // when !ok
  std::string error_file, error;                // when !ok
  double seconds = 0;  // its own work (frames overlap: a run takes less than their sum)
  // Milliseconds of it reading the input, lighting (tracing to composite), writing; a frame read
  // only for the temporal stage (a window's neighbour, the EMA's pre-roll) counts with the frame
  // it serves.
  double read_ms = 0, gi_ms = 0, write_ms = 0;
  std::size_t sanitized = 0;  // input values that were NaN or infinite, read as 0
  GuideStats guide;           // when ok, with a guide
};

// What became of a run's frames.
struct RunReport {
  std::vector<FrameReport> frames;  // those attempted, in order
  int total = 0;                    // the frames the run was to write
  int failed() const;
  int skipped() const;
};

// What run_sequence tells its caller as it goes, from the thread that called it.
struct RunCallbacks {
  // Once the frames are known, before any is computed: how many the run is to write, and how
  // many of those are already there (skip_existing) and will not be made again.
  std::function<void(int total, int reused)> on_start;
  // After each frame, written, reused or failed; `done` frames of `total` are behind.
  std::function<void(const FrameReport&, int done, int total)> on_frame;
  // Each frame made (not reused), before it is written: its G-buffer (without motion) and results,
  // their colours in the working space.
  std::function<void(const GBuffer&, const FrameResult&)> on_result;
};

}  // namespace ssgi
