// The channel layout presets as data: lib/src/io/layout_presets.json, compiled into the library
// by CMake (lib/src/io/layout_presets.cpp.in) and read by io/layout.cpp.
#pragma once

namespace ssgi::detail {

// The text of layout_presets.json.
extern const char* const kLayoutPresetsJson;

}  // namespace ssgi::detail
