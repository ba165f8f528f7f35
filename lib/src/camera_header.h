// Cameras from EXR header attributes and sidecar files (internal: uses OIIO types).
#pragma once

#include <OpenImageIO/imageio.h>

#include <optional>
#include <string>

#include "ssgi/camera.h"

namespace ssgi::detail {

// The camera the header of `spec` describes (worldToCamera + worldToNDC, worldToScreen,
// Nuke's exr/ prefixed names, V-Ray's cameraTransform, Arnold's lens attributes), or nullopt
// when the header has none. Throws Error(kInput) naming `file` when the attributes are there
// but unusable (singular, not a perspective projection).
std::optional<Camera> camera_from_header(const OIIO::ImageSpec& spec, const Box2i& display_window,
                                         const std::string& file);

// The camera of `frame` in the sidecar JSON file `json_path` (format: man/ssgi.1, CAMERAS).
// Throws Error(kIO) when unreadable, Error(kInput) when malformed or the frame is absent.
Camera camera_from_sidecar(const std::string& json_path, int frame,
                           const Box2i& display_window);

}  // namespace ssgi::detail
