// The plan: which stages run and which channels are read, from the inputs and the settings.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "io/frame_reader.h"
#include "ssgi/plan.h"
#include "ssgi/settings.h"

namespace ssgi {

// What a run does, decided once from what the inputs provide and what the user asked: the
// only place that chooses stages, channels and buffers.
struct Plan {
  RoleMask roles = 0;            // the channels the reader reads
  bool gather_emission = false;  // emission is part of the light rays pick up
  int trace_scale = 1;           // data-window pixels per trace sample, each axis
  bool env_map = false;          // misses look up an environment map
  bool denoise = false;
  TemporalMode temporal = TemporalMode::kNone;
  int multiframe = 0;  // frames each side that missed rays are continued in (0: none)
  bool views = false;  // missed rays continued in the shot's views (--view) first
  bool guide = false;  // the light is the control variate of a guide's (--guide, gi/guide.h)
  std::vector<std::string> reasons;   // one line per decision, for `ssgi info` and -v
  std::vector<std::string> warnings;  // what `ssgi run` and `ssgi info` warn about, one line each
};

// What the pipeline and a run may hold besides the frames' planes (a run chooses it for its
// memory limit). It does not change the light.
struct PipelineMemory {
  // The bytes of hits (4 a ray) the Embree reference keeps for the bounces after the first; the
  // rows beyond them are traced again for each bounce.
  std::size_t reference_hits_bytes = std::size_t{1} << 30;
  // Frames read, lit and written at once: 3 reads the next and writes the last while lighting
  // one, 2 overlaps two of those, 1 does one after the other.
  int frames_in_flight = 2;
  // The window's frames waiting for their later neighbours hold only their light on the trace
  // grid and are decoded again to be finished: the least memory, the same bits.
  bool read_twice = false;
  // A frame's passes are read after its composite (a callback, the preview), which is then
  // written beside them rather than over them.
  bool passes_read_after_composite = false;
};

// Decides the plan for `sequence` under `settings`. Throws Error(kUsage) for a setting out of
// range and Error(kInput) naming the first frame when it lacks the direct light or the albedo.
Plan make_plan(const SequenceInfo& sequence, const GiSettings& settings);

}  // namespace ssgi
