// Pinhole cameras fitted to a frame's world-space position pass (internal): for renderers that
// write positions but no camera (Blender/Cycles as it writes its multilayer EXRs).
//
// The fit: surface pixels on a lattice of about 64 x 64, away from silhouettes (renderers filter
// the position pass over the pixel, so that at an edge it is a blend of two surfaces); the 3x4
// projection from them by the direct linear transform in normalised coordinates (Hartley and
// Zisserman, "Multiple View Geometry", 4.4 and 7.1), decomposed into intrinsics and pose (RQ);
// then refined by Levenberg-Marquardt on the reprojection error with the library's model (fx,
// fy, cx, cy, no skew), one round of outlier rejection, and refined again.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ssgi/camera.h"
#include "ssgi/image.h"

namespace ssgi::detail {

// One surface point: its world position and the display-window pixel centre it was seen at.
struct PositionSample {
  Imath::V3d world;
  double px = 0, py = 0;
};

// The samples of a frame's lattice whose 3x3 neighbourhood is surface with smooth depth.
// `position` holds X, Y, Z planes and `distance` one plane of a distance along the view (planar
// or radial depth, any unit) that is +inf or NaN where there is no surface; both cover `data`.
// `lattice_points` receives how many lattice points there were.
std::vector<PositionSample> position_samples(const Image& position, const Image& distance,
                                             const Box2i& display, const Box2i& data,
                                             std::size_t* lattice_points = nullptr);

// Why a fit was refused, and what it found.
struct CameraFitResult {
  bool ok = false;
  Camera camera;             // valid when ok
  double residual_px = 0;    // RMS reprojection error of the kept samples
  std::size_t samples = 0;   // samples used, after outlier rejection
  std::size_t rejected = 0;  // samples dropped as outliers
  std::string problem;       // when !ok: one line saying why, ending in what to do
};

// Above this RMS reprojection error (pixels) a fit is refused. A pinhole renderer's own
// position pass fits to ~1e-5 px (Cycles' in the sample data), and one filtered over the pixel
// to a small fraction of a pixel away from silhouettes; a fisheye, lens distortion or motion
// blur bends positions by pixels. Half a pixel is where reprojecting the frame's light with the
// fitted camera would start putting it on the neighbouring pixel.
constexpr double kMaxFitResidualPx = 0.5;

// Fits a pinhole camera (library conventions: x right, y up, +z forward, pixel centres at
// i + 0.5) to `samples`. `pass_name` names the position pass in source and messages, e.g.
// "ViewLayer.Position". Never throws: a refused fit has ok false and `problem` set.
CameraFitResult fit_camera_to_positions(const std::vector<PositionSample>& samples,
                                        std::size_t lattice_points, const std::string& pass_name);

// RMS distance in pixels between `samples`' pixel centres and their positions projected by
// `camera` (which needs a world transform); a point behind the camera counts as the width of
// the display window away.
double reprojection_rms_px(const Camera& camera, const std::vector<PositionSample>& samples,
                           const Box2i& display);

}  // namespace ssgi::detail
