// The slice tracer: a visibility bitmask over screen-space slices (Therrien et al. 2023,
// "Screen Space Indirect Lighting with Visibility Bitmask"), on the surface model of
// surface_model.h.
//
// A slice is the plane through the camera, the trace origin P and a screen direction: it holds
// every ray from P whose screen projection runs along that direction, either way. The
// cosine-weighted hemisphere is the union of the slices over the directions in [0, pi), with
// measure |n_p| cos(theta - gamma) |sin theta| dtheta dphi (theta the angle from the view
// vector in the slice, n_p the normal projected into it at angle gamma): each slice's half-disc
// of directions is cut into 32 sectors of equal measure, one bit each, with a random rotation,
// so that a bit is one stratified ray. One march outwards along each side samples the mesh:
// a sample's slab (front z to back z (1 + thickness)) shadows the sectors between the angles
// of its two ends, and so does the strip between two consecutive samples of one continuous
// surface. A sector first shadowed by a sample is a ray that hits it first: it brings that
// sample's light. Sectors left at the end are misses. With many slices, sectors and samples
// this is the march's and the reference's answer on the same surface model.
#pragma once

#include "gi/continuation.h"
#include "gi/gather.h"
#include "gi/misses.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// settings.slices slices per trace origin, settings.max_steps samples along each side of each.
// The result is the same for any thread count. With `missed`, also the directions of the misses
// (each slice's missed sectors cut into `missed_runs` runs, one sector's ray drawn from each,
// weighing its run) for the views or the shot's other frames to continue (continuation.h).
WeightedHits trace_slices(const GBuffer& g, const TraceGrid& grid, const GiSettings& settings,
                          const MissModel& misses, MissedRays* missed = nullptr,
                          int missed_runs = kMultiframeRunsPerSlice);

}  // namespace ssgi::detail
