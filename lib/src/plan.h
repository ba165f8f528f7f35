// The plan: which stages run and which channels are read, from the inputs and the settings.
#pragma once

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
  int multiframe = 0;                // frames each side that missed rays are continued in (0: none)
  bool views = false;                // missed rays continued in the shot's views (--view) first
  std::vector<std::string> reasons;  // one line per decision, for `ssgi info` and -v
  std::vector<std::string> warnings;  // what `ssgi run` and `ssgi info` warn about, one line each
};

// Decides the plan for `sequence` under `settings`. Throws Error(kUsage) for a setting out of
// range and Error(kInput) naming the first frame when it lacks the direct light or the albedo.
Plan make_plan(const SequenceInfo& sequence, const GiSettings& settings);

}  // namespace ssgi
