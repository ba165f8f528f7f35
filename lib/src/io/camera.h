// Cameras from matrices (EXR header attributes, a lat-long view's worldToCamera) and the checked
// inverse they all use.
#pragma once

#include <Imath/ImathMatrix.h>

#include <string>

#include "ssgi/camera.h"
#include "ssgi/image.h"

namespace ssgi {

// The inverse of a 4x4 matrix. Throws Error(kInput) when singular: |det| below 1e-12 times the
// product of the row lengths (a scale-free test), or any entry not finite.
Imath::M44d inverse_checked(const Imath::M44d& m);

// A lat-long camera (Projection::kLatLong) over `display_window` with the header's
// worldToCamera, whose camera space looks along -z with +y up (as Blender, Arnold, Houdini and
// USD write it): flipped to the library's +z forward. Source "header worldToCamera (lat-long)".
// Throws Error(kInput) naming `file` on a singular or non-finite matrix.
Camera latlong_camera(const Imath::M44d& world_to_camera, const Box2i& display_window,
                      const std::string& file);

// A camera from OpenEXR's standard worldToCamera and worldToNDC attributes (NDC (0,0) top-left,
// (1,1) bottom-right of the display window, divide by w), off-centre shifts included. The
// file's camera axes may point either way: world_to_camera is flipped to x right, y up,
// +z forward. Throws Error(kInput) naming `file` on a singular or non-finite matrix, or when
// inverse(worldToCamera) * worldToNDC is not a pinhole projection at the camera origin
// (orthographic, skewed, tilted) or looks like a -1..1 screen matrix.
Camera camera_from_matrices(const Imath::M44d& world_to_camera, const Imath::M44d& world_to_ndc,
                            const Box2i& display_window, const std::string& file);

}  // namespace ssgi
