// Reading G-buffer sequences from renderer EXRs: the sequence probed from its first frame, and
// each frame's passes converted to the library's conventions.
#pragma once

#include <string>

#include "io/sequence_info.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"

namespace ssgi {

class ColorManagement;

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

// Sets how many threads OpenImageIO and OpenEXR use (0: their default).
void set_io_threads(int threads);

}  // namespace ssgi
