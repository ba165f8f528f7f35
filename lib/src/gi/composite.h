// The composite stage: the output layers from the G-buffer and the indirect light.
#pragma once

#include "ssgi/gbuffer.h"

namespace ssgi::detail {

// indirect 0 on surfaces without diffuse albedo (all three channels 0); gi = albedo x
// indirect; composite = direct + emission + gi on surfaces, the input beauty
// (or 0) on background pixels; alpha from the beauty, else 1; the coverage, when given, kept
// within [0, 1] and 0 on background.
FrameResult composite_frame(const GBuffer& g, Image indirect, Image coverage = {});

// composite_frame for a G-buffer not needed after it: gi is written over its albedo and the
// composite over its beauty (when that has an alpha), so that compositing takes no plane
// besides the frame's own. Leaves *g without albedo and beauty.
FrameResult composite_frame_in_place(GBuffer* g, Image indirect, Image coverage = {});

}  // namespace ssgi::detail
