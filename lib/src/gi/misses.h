// What rays that hit nothing bring (MissMode), and the bounce loop that re-gathers over the
// same rays. Shared by the screen-space march and the Embree reference.
#pragma once

#include "march.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// How enclosed the camera is, in [0, 1], from the frame's border: the fraction of border
// pixels whose surface runs alongside the view on its side (a ceiling along the top edge faces
// down, a floor along the bottom faces up, side walls face inwards). A room seen from inside
// scores near 1; a set seen from outside (a backdrop along the top, sky) scores low.
double enclosure(const GBuffer& g);

// The weight of the frame estimate for misses: 0 for kEnvironment and kExtend; the fraction of
// the frame that shows surfaces for kFrame; for kAuto that fraction times a smooth ramp of the
// enclosure from 0 at 0.4 to 1 at 0.6, so that a score near the threshold does not switch
// abruptly between frames.
double closure_weight(const GBuffer& g, MissMode mode);

}  // namespace ssgi::detail
