// Cameras: how they project, a camera from a field of view, and where a run takes them from.
#pragma once

#include <Imath/ImathMatrix.h>
#include <Imath/ImathVec.h>

#include <optional>
#include <string>

#include "ssgi/image.h"

namespace ssgi {

// How a camera maps directions to pixels. A frame is always a pinhole; a view (--view) may be
// a latitude-longitude panorama, which the reader turns into six pinhole cube faces.
enum class Projection {
  kPinhole,
  // Equirectangular over the display window, the centre along +z, longitude growing towards +x,
  // the top row up (+y); fx, fy are pixels per radian, depth the distance along the ray.
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
  // pass); without it (--fov), world-space inputs (normals, env maps) are taken as camera-space.
  bool has_world_transform = false;
  Imath::M44d world_to_camera;  // row vectors, as OpenEXR stores it: p' = p * M; identity
  std::string source;  // where it came from, e.g. "sidecar cam.json", "--fov", "position pass"
  std::optional<double> fit_residual_px;  // fitted to the position pass: its RMS error, pixels

  // Horizontal field of view over `display_width` pixels, in degrees.
  double hfov_deg(int display_width) const;
  // Camera-space point to continuous display-window pixel coordinates: a pinhole's for p.z > 0
  // only (the caller tests z), a lat-long's for any p but the origin.
  void project(const Imath::V3d& p, double* px, double* py) const;
  // Continuous display-window pixel coordinates and planar depth z to a camera-space point (for
  // a lat-long camera, z is the distance along the pixel's ray).
  Imath::V3d unproject(double px, double py, double z) const;
  // Unit camera-space view direction through continuous pixel coordinates.
  Imath::V3d view_dir(double px, double py) const;
};

// A centred camera with the given horizontal field of view over the display window, pixels
// `pixel_aspect` (OpenEXR's pixelAspectRatio) wide: fy = fx * pixel_aspect. No world transform;
// source "--fov". Throws Error(kUsage) unless 0 < hfov_deg < 180 and pixel_aspect > 0.
Camera camera_from_fov(double hfov_deg, const Box2i& display_window, double pixel_aspect = 1.0);

// Where the user told the camera to come from; when both are empty the EXR header decides.
// The sidecar wins over --fov, which wins over the header.
struct CameraOptions {
  double hfov_deg = 0;  // --fov: > 0 gives a static camera with this horizontal field of view
  std::string sidecar;  // --camera FILE.json: per-frame cameras (format in man/ssgi-cameras.7)
  // A view's (--view): a lat-long view's camera is its header's worldToCamera alone.
  Projection projection = Projection::kPinhole;
};

}  // namespace ssgi
