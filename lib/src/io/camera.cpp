// Pinhole camera maths: 4x4 matrices in Imath's row-vector convention, projection to
// display-window pixels, and cameras built from a field of view or from OpenEXR's
// worldToCamera/worldToNDC pair.
#include "io/camera.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "throw.h"

namespace ssgi {
namespace {

constexpr double kPi = 3.14159265358979323846;

double rad_to_deg(double r) { return r * (180.0 / kPi); }
double deg_to_rad(double d) { return d * (kPi / 180.0); }

bool all_finite(const Imath::M44d& a) {
  for (const auto& row : a.x)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

// Scales the camera-space axes by s = (sx, sy, sz), each +-1: world_to_camera * S, and the
// camera-to-NDC matrix S^-1 * P = S * P, so that the composition world -> NDC is unchanged.
void flip_camera_axes(const double s[3], Imath::M44d* world_to_camera, Imath::M44d* camera_to_ndc) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 3; ++c) world_to_camera->x[r][c] *= s[c];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) camera_to_ndc->x[r][c] *= s[r];
}

std::string format_number(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

}  // namespace

Imath::M44d inverse_checked(const Imath::M44d& m) {
  // Gauss-Jordan with partial pivoting. The singularity test is relative: |det| against
  // Hadamard's bound (the product of the row lengths), so that it does not depend on the
  // scene's units or on how large the translation is.
  double bound = 1;
  for (const auto& row : m.x) {
    double len2 = 0;
    for (double v : row) len2 += v * v;
    bound *= std::sqrt(len2);
  }
  if (!all_finite(m) || !(bound > 0)) throw_input({}, "singular or non-finite 4x4 matrix");

  double a[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      a[i][j] = m[i][j];
      a[i][j + 4] = i == j ? 1 : 0;
    }
  double det = 1;
  for (int col = 0; col < 4; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
    if (pivot != col) {
      std::swap(a[pivot], a[col]);
      det = -det;
    }
    const double p = a[col][col];
    det *= p;
    if (p == 0) break;
    for (double& v : a[col]) v /= p;
    for (int r = 0; r < 4; ++r) {
      if (r == col) continue;
      const double f = a[r][col];
      if (f == 0) continue;
      for (int j = 0; j < 8; ++j) a[r][j] -= f * a[col][j];
    }
  }
  // 1e-12: far below what a float-stored camera matrix can lose to rounding (~1e-7), far above
  // the cancellation noise of an exactly singular one (~1e-16).
  const double relative_det = std::abs(det) / bound;
  if (!(relative_det > 1e-12))
    throw_input({},
                "singular 4x4 matrix (relative determinant " + format_number(relative_det) + ")");
  Imath::M44d r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r[i][j] = a[i][j + 4];
  return r;
}

double Camera::hfov_deg(int display_width) const {
  if (projection == Projection::kLatLong) return 360.0;
  // Left and right edges separately, so that an off-centre principal point gives the angle
  // the image really spans.
  return rad_to_deg(std::atan(cx / fx) + std::atan((display_width - cx) / fx));
}

void Camera::project(const Imath::V3d& p, double* px, double* py) const {
  if (projection == Projection::kLatLong) {
    const double r = std::sqrt(p.dot(p));
    *px = cx + fx * std::atan2(p.x, p.z);
    *py = cy - fy * std::asin(std::clamp(p.y / r, -1.0, 1.0));
    return;
  }
  *px = cx + fx * p.x / p.z;
  *py = cy - fy * p.y / p.z;
}

Imath::V3d Camera::unproject(double px, double py, double z) const {
  if (projection == Projection::kLatLong) return view_dir(px, py) * z;
  return {(px - cx) / fx * z, (cy - py) / fy * z, z};
}

Imath::V3d Camera::view_dir(double px, double py) const {
  if (projection == Projection::kLatLong) {
    const double longitude = (px - cx) / fx, latitude = (cy - py) / fy;
    return {std::cos(latitude) * std::sin(longitude), std::sin(latitude),
            std::cos(latitude) * std::cos(longitude)};
  }
  const Imath::V3d d((px - cx) / fx, (cy - py) / fy, 1.0);
  return d / std::sqrt(d.dot(d));
}

Camera latlong_camera(const Imath::M44d& world_to_camera, const Box2i& display_window,
                      const std::string& file) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(world_to_camera[i][j]))
        throw_input(file, "worldToCamera has a value that is not finite");
  try {
    inverse_checked(world_to_camera);
  } catch (const Error& e) {
    throw_input(file, std::string("worldToCamera: ") + e.what());
  }
  Camera c;
  c.projection = Projection::kLatLong;
  const double w = display_window.width(), h = display_window.height();
  c.fx = w / (2 * M_PI);
  c.fy = h / M_PI;
  c.cx = w / 2;
  c.cy = h / 2;
  // -z forward to +z forward: the third column negated (row-vector convention).
  c.world_to_camera = world_to_camera;
  for (int i = 0; i < 4; ++i) c.world_to_camera[i][2] = -world_to_camera[i][2];
  c.has_world_transform = true;
  c.source = "header worldToCamera (lat-long)";
  return c;
}

Camera camera_from_fov(double hfov_deg, const Box2i& display_window, double pixel_aspect) {
  if (!(hfov_deg > 0 && hfov_deg < 180))
    throw_usage("field of view " + format_number(hfov_deg) + " degrees is outside (0, 180)");
  if (!(pixel_aspect > 0 && std::isfinite(pixel_aspect)))
    throw_usage("pixel aspect ratio " + format_number(pixel_aspect) + " is not positive");
  if (display_window.empty()) throw_input({}, "empty display window");
  Camera c;
  const double w = display_window.width(), h = display_window.height();
  c.fx = 0.5 * w / std::tan(0.5 * deg_to_rad(hfov_deg));
  // A pixel pixel_aspect times wider than tall spans pixel_aspect times more of the image
  // plane horizontally than vertically: 1/fx = pixel_aspect / fy.
  c.fy = c.fx * pixel_aspect;
  c.cx = 0.5 * w;
  c.cy = 0.5 * h;
  c.source = "--fov";
  return c;
}

Camera camera_from_matrices(const Imath::M44d& world_to_camera, const Imath::M44d& world_to_ndc,
                            const Box2i& display_window, const std::string& file) {
  if (display_window.empty()) throw_input(file, "empty display window");
  if (!all_finite(world_to_camera)) throw_input(file, "worldToCamera has non-finite entries");
  if (!all_finite(world_to_ndc)) throw_input(file, "worldToNDC has non-finite entries");
  Imath::M44d camera_to_world;
  try {
    camera_to_world = inverse_checked(world_to_camera);
  } catch (const Error& e) {
    throw_input(file, std::string("worldToCamera: ") + e.what());
  }
  Imath::M44d w2c = world_to_camera;
  Imath::M44d p = camera_to_world * world_to_ndc;

  // (X, Y, Z, W) = (x, y, z, 1) * P. A pinhole at the camera origin looking along z has
  // W = a * z only, X = P00 x + P20 z, Y = P11 y + P21 z: anything else is a projection this
  // library cannot represent (orthographic, tilted image plane, skew, a centre of projection
  // away from the camera). Tolerances allow float-stored matrices (~1e-7 relative); entries
  // that carry a length are compared against the camera's distance from the world origin,
  // whose size sets how much rounding they pick up.
  constexpr double kTol = 1e-5;
  const double a = p[2][3];
  const double w_scale = std::max({std::abs(p[0][3]), std::abs(p[1][3]), std::abs(a)});
  if (!(std::abs(a) > 1e-9 * std::max(w_scale, std::abs(p[3][3]))))
    throw_input(file,
                "worldToNDC is not a perspective projection (w does not depend on camera z: "
                "orthographic or degenerate)");
  if (std::abs(p[0][3]) > kTol * std::abs(a) || std::abs(p[1][3]) > kTol * std::abs(a))
    throw_input(file,
                "worldToNDC is not a pinhole projection along the camera's z axis (w depends on "
                "camera x or y)");
  const Imath::V3d eye = camera_to_world.translation();
  const double length_scale = 1 + std::sqrt(eye.dot(eye));
  if (std::abs(p[3][3]) > kTol * std::abs(a) * length_scale)
    throw_input(file, "worldToNDC's centre of projection is not at the worldToCamera origin");

  // Normalise to the library's camera space (x right, y up, +z forward): whatever axis the
  // file's camera space points the other way is flipped in world_to_camera, so nothing
  // downstream sees the renderer's handedness. OpenEXR's own text has x pointing left; the
  // sample data, RenderMan and Nuke have it pointing right; both come out the same here.
  const double flip_z[3] = {1, 1, a < 0 ? -1.0 : 1.0};
  flip_camera_axes(flip_z, &w2c, &p);
  const double w = display_window.width(), h = display_window.height();
  const double az = p[2][3];
  const double flip_xy[3] = {p[0][0] < 0 ? -1.0 : 1.0, p[1][1] > 0 ? -1.0 : 1.0, 1};
  flip_camera_axes(flip_xy, &w2c, &p);

  Camera c;
  // NDC x = (P00 x + P20 z + P30) / (a z) and pixel x = NDC x * W (pixel i's centre is NDC
  // (i + 0.5) / W); likewise for y, whose NDC axis points down.
  c.fx = w * p[0][0] / az;
  c.fy = -h * p[1][1] / az;
  c.cx = w * p[2][0] / az;
  c.cy = h * p[2][1] / az;
  if (!(c.fx > 0 && c.fy > 0 && std::isfinite(c.fx) && std::isfinite(c.fy)))
    throw_input(file, "worldToNDC has a zero or non-finite focal length");
  if (std::abs(p[1][0]) > kTol * std::abs(p[0][0]) || std::abs(p[0][1]) > kTol * std::abs(p[1][1]))
    throw_input(file, "worldToNDC has skew or image-plane rotation");
  if (std::abs(p[3][0]) > kTol * std::abs(p[0][0]) * length_scale ||
      std::abs(p[3][1]) > kTol * std::abs(p[1][1]) * length_scale)
    throw_input(file, "worldToNDC's centre of projection is not at the worldToCamera origin");
  // A principal point on the display window's top-left corner is how a -1..1 screen-space
  // matrix looks when a renderer writes it under the name worldToNDC (3Delight has done so):
  // reading it as NDC would put the image centre in the corner, so say what is wrong instead.
  if (std::abs(c.cx) < 1e-6 * w && std::abs(c.cy) < 1e-6 * h)
    throw_input(file,
                "worldToNDC maps the optical axis to the display window's corner: it looks "
                "like a screen-space (-1..1) matrix, not NDC; give --fov or --camera");
  c.has_world_transform = true;
  c.world_to_camera = w2c;
  c.source = "worldToCamera/worldToNDC";
  return c;
}

}  // namespace ssgi
