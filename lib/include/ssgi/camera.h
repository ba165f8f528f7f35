// Pinhole cameras: where they come from (EXR header, sidecar, --fov) and how they project.
#pragma once

#include <Imath/ImathMatrix.h>
#include <Imath/ImathVec.h>

#include <optional>
#include <string>

#include "ssgi/image.h"

namespace ssgi {

// The inverse of a 4x4 matrix. Throws Error(kInput) when singular: |det| below 1e-12 times the
// product of the row lengths (a scale-free test), or any entry not finite.
Imath::M44d inverse_checked(const Imath::M44d& m);

// How a camera maps directions to pixels. A frame is always a pinhole; a view (--view) may be
// a latitude-longitude panorama, which the reader turns into six pinhole cube faces.
enum class Projection {
  kPinhole,
  // Equirectangular, 360 x 180 degrees over the display window: the centre looks along +z, the
  // longitude grows to the right (towards +x), the top row looks straight up (+y). fx and fy
  // are pixels per radian (W / 2 pi, H / pi), (cx, cy) the display window's centre, and depth
  // is the distance from the camera along the pixel's ray.
  kLatLong,
};

// A pinhole camera in the library's camera space (OpenEXR worldToCamera: x right, y up,
// +z forward, depth positive in front) projecting onto display-window pixels, y down.
// Pixel (i, j) has its centre at (i + 0.5, j + 0.5), i.e. NDC ((i+0.5)/W, (j+0.5)/H).
struct Camera {
  // px = cx + fx * x / z,  py = cy - fy * y / z  (display-window pixel units, origin at the
  // display window's top-left corner, so the window spans [0, W] x [0, H]). fx, fy > 0; an
  // off-centre (shifted) camera has (cx, cy) away from (W/2, H/2).
  double fx = 1, fy = 1, cx = 0, cy = 0;
  Projection projection = Projection::kPinhole;
  // Whether world_to_camera is known (header matrices, sidecar, or a fit to the position
  // pass); a --fov camera has none,
  // and then world-space inputs (normals, env maps) are taken as camera-space.
  bool has_world_transform = false;
  // Imath's row-vector convention, as OpenEXR headers store it: p' = p * M, translation in
  // row 3. Identity by default.
  Imath::M44d world_to_camera;
  // Human-readable origin, e.g. "header worldToCamera/worldToNDC", "sidecar cam.json", "--fov",
  // "position pass ViewLayer.Position (fit, residual 0.004 px)".
  std::string source;
  // For a camera fitted to the frame's world position pass: the fit's RMS reprojection error
  // in pixels. Empty for every other source.
  std::optional<double> fit_residual_px;

  // Horizontal field of view over `display_width` pixels, in degrees.
  double hfov_deg(int display_width) const;
  // Camera-space point to continuous display-window pixel coordinates. For a pinhole camera
  // meaningful for p.z > 0 only: the caller tests z (behind the camera the result is mirrored or
  // infinite); for a lat-long camera any p but the origin (the longitude and latitude of its
  // direction).
  void project(const Imath::V3d& p, double* px, double* py) const;
  // Continuous display-window pixel coordinates and planar depth z to a camera-space point (for
  // a lat-long camera, z is the distance along the pixel's ray).
  Imath::V3d unproject(double px, double py, double z) const;
  // Unit camera-space view direction through continuous pixel coordinates.
  Imath::V3d view_dir(double px, double py) const;
};

// A centred camera with the given horizontal field of view over the display window and
// `pixel_aspect` = OpenEXR pixelAspectRatio (pixel width / height): fy = fx * pixel_aspect,
// since a wider pixel covers more of the image plane across than down. No world transform;
// source "--fov". Throws Error(kUsage) unless 0 < hfov_deg < 180 and pixel_aspect > 0.
Camera camera_from_fov(double hfov_deg, const Box2i& display_window, double pixel_aspect = 1.0);

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

namespace ssgi {

// Where the user told the camera to come from; when both are empty the EXR header decides.
// The sidecar wins over --fov, which wins over the header.
struct CameraOptions {
  double hfov_deg = 0;  // --fov: > 0 gives a static camera with this horizontal field of view
  std::string sidecar;  // --camera FILE.json: per-frame cameras (format in man/ssgi-cameras.7)
  // A view's (--view): a lat-long view's camera is its header's worldToCamera alone.
  Projection projection = Projection::kPinhole;
};

}  // namespace ssgi
