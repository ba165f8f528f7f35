// The Embree reference: hemisphere rays traced against a mesh built from the depth buffer with
// the same surface model as the march (surface_model.h), so that comparing `ssgi run` with
// `ssgi reference` measures the march and the denoiser and nothing else. Embree is used here
// and nowhere else.
#pragma once

#include "environment.h"
#include "march.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// Traces settings.rays cosine-weighted rays per surface pixel with Embree and records, like
// march_screen_space, the hit pixel of each ray or a miss (with the environment it saw).
RayHits trace_reference(const GBuffer& g, const GiSettings& settings, const Environment& env);

}  // namespace ssgi::detail
