// The preview of `ssgi run --preview`: a frame's composite as a display-referred 8-bit picture.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "io/color.h"
#include "ssgi/gbuffer.h"

namespace ssgi::detail {

// Throws Error(kUsage) unless `pattern` ends in .png, .jpg or .jpeg (any case).
void check_preview_pattern(const std::string& pattern);

// The header attributes a preview carries: `provenance` and the display and view it went
// through, so that --skip-existing can tell whether one on disk is still the one a run makes.
std::vector<std::pair<std::string, std::string>> preview_attributes(
    const std::vector<std::pair<std::string, std::string>>& provenance,
    const ColorManagement& color);

// Writes `composite` (working space, covering `frame`'s data window; alpha not shown) through
// the display and view of `color`, the size of the display window (black where the data window
// does not reach), as an 8-bit PNG or JPEG, atomically. Throws Error(kIO) naming `path`.
void write_preview(const std::string& path, const GBuffer& frame, const Image& composite,
                   const ColorManagement& color,
                   const std::vector<std::pair<std::string, std::string>>& attributes);

}  // namespace ssgi::detail
