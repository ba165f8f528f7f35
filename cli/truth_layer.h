// The input layer that --truth names (ssgi sweep, ssgi preview): a renderer's own answer, such as
// Cycles' path-traced DiffInd, to measure ssgi's indirect light against.
#pragma once

#include <string>

#include "io/layout.h"

namespace ssgi_cli {

// The full name of the R, G, B layer `layer` names in `file`: that exact name, else the one
// layer whose name ends in .LAYER (Blender's view layer prefix: DiffInd is ViewLayer.DiffInd).
// Throws Error(kInput) naming `path` when there is none or more than one.
std::string resolve_truth_layer(const ssgi::FileChannels& file, const std::string& layer,
                                const std::string& path);

}  // namespace ssgi_cli
