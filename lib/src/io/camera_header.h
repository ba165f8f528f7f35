// Cameras from EXR header attributes and sidecar files (internal: uses OIIO types).
//
// CAMERA SIDECAR (--camera FILE.json)
//
// A JSON object. Per-frame cameras go in "frames", an array of objects, each with an integer
// "frame" and either
//
//   "worldToCamera" and "worldToNDC": 16 numbers each (or 4 rows of 4 numbers), row-major in
//       Imath's row-vector convention (p' = p * M, translation in the last row): the same
//       matrices as OpenEXR's header attributes of those names. NDC (0,0) is the top-left and
//       (1,1) the bottom-right corner of the display window, after the divide by w. Camera
//       space may point its axes either way: it is normalised to x right, y up, +z forward.
//   or "hfov_deg": the horizontal field of view over the display window in degrees, centred,
//       with optional "pixel_aspect" (pixel width / height, default 1) and optional
//       "worldToCamera" (16 numbers, camera space x right, y up, +z forward), which lets
//       world-space normals be used.
//
// The same keys at the top level give a static camera for every frame that "frames" does not
// list, e.g. {"hfov_deg": 40}. When an entry has both the matrix pair and "hfov_deg", the
// matrices win: they also carry the camera's position and any off-centre shift. Other keys are
// ignored, so the camera.json Blender exports beside the sample data is read as it is.
// Errors: an unreadable file is an I/O error (exit 4); invalid JSON, a frame that is not there,
// or a camera that is not a usable perspective camera is an input error (exit 3).
#pragma once

#include <OpenImageIO/imageio.h>

#include <optional>
#include <string>

#include "ssgi/camera.h"

namespace ssgi::detail {

// The camera the header of `spec` describes, or nullopt when the header has none. Tried in
// this order (see camera_header.cpp for the source of each convention):
//   worldToCamera + worldToNDC      OpenEXR standard attributes (RenderMan, 3Delight, Nuke)
//   exr/worldToCamera + exr/worldToNDC, and the names OIIO before 2.2 gave them
//   worldToCamera + worldToScreen   with screenWindowCenter, screenWindowWidth and
//                                   pixelAspectRatio mapping screen space to NDC
//   cameraTransform + cameraFov     V-Ray (OIIO renames cameraTransform to "worldtocamera")
//   CameraFov or CameraFocalLength + CameraFilmApertureHorizontal (+ worldToCamera)   Arnold
//   rs/camera/fov (+ rs/camera/transform), or RSCameraFOV (+ RSCameraTransform)     Redshift
//   unreal/camera/<pass>/fov (+ unreal/camera/curPos/*, curRot/*)       Unreal Movie Render Queue
// Karma's render delegate hands husk worldToCamera and worldToScreen, and RenderMan's display
// drivers get Nl and NP, which OpenEXR writers store under the same two names: both are read as
// the OpenEXR pair (the names are not confirmed on files from either).
// Throws Error(kInput) naming `file` when the attributes are there but unusable (singular,
// not a perspective projection).
std::optional<Camera> camera_from_header(const OIIO::ImageSpec& spec, const Box2i& display_window,
                                         const std::string& file);

// A lat-long camera (latlong_camera) from the header's worldToCamera, or nullopt when it has
// none. Throws Error(kInput) naming `file` when the matrix is unusable.
std::optional<Camera> latlong_camera_from_header(const OIIO::ImageSpec& spec,
                                                 const Box2i& display_window,
                                                 const std::string& file);

// The camera of `frame` in the sidecar JSON file `json_path` (format above and in
// man/ssgi-cameras.7). Throws Error(kIO) when unreadable, Error(kInput) when malformed or the frame
// is absent.
Camera camera_from_sidecar(const std::string& json_path, int frame, const Box2i& display_window);

}  // namespace ssgi::detail
