// A guide's frame as read (io/guide.h): what the frame reader hands the lighting stage.
#pragma once

#include "ssgi/image.h"

namespace ssgi::detail {

// One frame of a guide, in the working colour space.
struct GuideFrame {
  int fraction = 1;  // GuideInfo::fraction
  Image light;       // 3 channels at the guide's resolution: indirect light without albedo
  // 3 channels, 1 where `light` is known, 0 where the pass includes the albedo and that is 0
  // (nothing to divide by); empty when everything is known.
  Image known;
  Image depth;  // 1 channel at the guide's resolution: planar depth, +inf without a surface
};

}  // namespace ssgi::detail
