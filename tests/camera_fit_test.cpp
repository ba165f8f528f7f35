// Tests of the camera fit to a world position pass on analytic scenes: a known camera seeing a
// smooth surface is recovered (lens shift, non-square pixels, both handednesses), and what is
// not a pinhole camera or cannot determine one is refused with its reason.
#include "io/camera_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "ssgi/camera.h"

namespace ssgi::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Rotation by `deg` about a unit axis, row-vector convention (p' = p * R).
Imath::M44d Rotation(Imath::V3d axis, double deg) {
  axis.normalize();
  const double a = deg * kPi / 180, c = std::cos(a), s = std::sin(a), t = 1 - c;
  const double x = axis.x, y = axis.y, z = axis.z;
  const double col[3][3] = {{t * x * x + c, t * x * y - s * z, t * x * z + s * y},
                            {t * x * y + s * z, t * y * y + c, t * y * z - s * x},
                            {t * x * z - s * y, t * y * z + s * x, t * z * z + c}};
  Imath::M44d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i][j] = col[j][i];
  return r;
}

// A camera at `eye` whose world_to_camera is a rotation, times a mirror of z when `mirrored`
// (a right-handed world such as Blender's seen in the library's left-handed camera space).
Camera KnownCamera(double fx, double fy, double cx, double cy, bool mirrored) {
  Camera c;
  c.fx = fx;
  c.fy = fy;
  c.cx = cx;
  c.cy = cy;
  c.has_world_transform = true;
  const Imath::V3d eye(0.7, -3.2, 1.6);
  Imath::M44d translate;
  translate.setTranslation(-eye);
  Imath::M44d mirror;
  if (mirrored) mirror[2][2] = -1;
  c.world_to_camera = translate * Rotation({0.3, -0.5, 0.8}, 37) * mirror;
  return c;
}

// The passes a renderer would write for `camera` seeing, at pixel centre (px, py), the point
// at planar depth depth_at(px, py); the depth plane is that depth, +inf where it is not finite.
struct Passes {
  Image position, distance;
  Box2i window;
};

Passes Render(const Camera& camera, int w, int h,
              const std::function<double(double, double)>& depth_at,
              const std::function<Imath::V3d(double, double, double)>& camera_point = {}) {
  Passes p{Image(w, h, 3), Image(w, h, 1), Box2i{0, 0, w, h}};
  const Imath::M44d camera_to_world = camera.world_to_camera.inverse();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double px = x + 0.5, py = y + 0.5, z = depth_at(px, py);
      if (!std::isfinite(z)) {
        p.distance.at(0, x, y) = std::numeric_limits<float>::infinity();
        continue;
      }
      const Imath::V3d c = camera_point ? camera_point(px, py, z) : camera.unproject(px, py, z);
      const Imath::V3d world = c * camera_to_world;
      p.distance.at(0, x, y) = static_cast<float>(z);
      for (int k = 0; k < 3; ++k) p.position.at(k, x, y) = static_cast<float>(world[k]);
    }
  }
  return p;
}

// A smooth, curved surface 3 to 6 m away: far from a plane.
double Hills(double px, double py) {
  return 4.5 + 1.2 * std::sin(px / 40.0) + 0.8 * std::cos(py / 25.0) + 0.002 * px;
}

CameraFitResult Fit(const Passes& p, const std::string& name = "ViewLayer.Position") {
  std::size_t lattice = 0;
  const std::vector<PositionSample> samples =
      position_samples(p.position, p.distance, p.window, p.window, &lattice);
  return fit_camera_to_positions(samples, lattice, name);
}

// Recovered intrinsics within 1e-3 relative (the brief's tolerance; exact data gives ~1e-9),
// the camera's rotation and position within 1e-6 (float-stored positions limit them to ~1e-7).
void ExpectSameCamera(const Camera& want, const Camera& got) {
  EXPECT_NEAR(got.fx, want.fx, 1e-3 * want.fx);
  EXPECT_NEAR(got.fy, want.fy, 1e-3 * want.fy);
  EXPECT_NEAR(got.cx, want.cx, 1e-3 * want.cx);
  EXPECT_NEAR(got.cy, want.cy, 1e-3 * want.cy);
  EXPECT_TRUE(got.has_world_transform);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(got.world_to_camera[i][j], want.world_to_camera[i][j], 1e-6) << i << "," << j;
  const Imath::V3d eye_want = want.world_to_camera.inverse().translation();
  const Imath::V3d eye_got = got.world_to_camera.inverse().translation();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(eye_got[k], eye_want[k], 1e-6) << k;
}

TEST(CameraFitTest, RecoversCameraWithLensShift) {
  // Principal point 18 px right of and 11 px above the centre of 320 x 180.
  for (bool mirrored : {true, false}) {
    SCOPED_TRACE(mirrored ? "mirrored" : "rotation");
    const Camera want = KnownCamera(280, 280, 178, 79, mirrored);
    const CameraFitResult fit = Fit(Render(want, 320, 180, Hills));
    ASSERT_TRUE(fit.ok) << fit.problem;
    ExpectSameCamera(want, fit.camera);
    EXPECT_LT(fit.residual_px, 1e-4);
    EXPECT_EQ(fit.rejected, 0u);
    EXPECT_GT(fit.samples, 3000u);
    ASSERT_TRUE(fit.camera.fit_residual_px.has_value());
    EXPECT_EQ(*fit.camera.fit_residual_px, fit.residual_px);
    EXPECT_EQ(fit.camera.source.rfind("position pass ViewLayer.Position (fit, residual ", 0), 0u)
        << fit.camera.source;
  }
}

TEST(CameraFitTest, RecoversNonSquarePixels) {
  // pixelAspectRatio 1.25: fy = 1.25 fx (camera_from_fov's convention).
  const Camera want = KnownCamera(200, 250, 160, 90, true);
  const CameraFitResult fit = Fit(Render(want, 320, 180, Hills));
  ASSERT_TRUE(fit.ok) << fit.problem;
  ExpectSameCamera(want, fit.camera);
  EXPECT_NEAR(fit.camera.fy / fit.camera.fx, 1.25, 1e-5);
}

TEST(CameraFitTest, FisheyeIsRefused) {
  // Equidistant fisheye: the angle from the axis is r / f, 180 degrees across the width.
  const Camera lens = KnownCamera(320 / kPi, 320 / kPi, 160, 90, true);
  const auto fisheye = [&](double px, double py, double distance) {
    const double dx = px - lens.cx, dy = lens.cy - py, r = std::hypot(dx, dy);
    const double theta = r / lens.fx;
    const double s = r > 0 ? std::sin(theta) / r : 1 / lens.fx;
    return Imath::V3d(dx * s, dy * s, std::cos(theta)) * distance;
  };
  const CameraFitResult fit = Fit(Render(lens, 320, 180, Hills, fisheye));
  ASSERT_FALSE(fit.ok);
  EXPECT_GT(fit.residual_px, 2.0);
  EXPECT_NE(fit.problem.find("position pass ViewLayer.Position does not fit a pinhole camera "
                             "(residual "),
            std::string::npos)
      << fit.problem;
  EXPECT_NE(fit.problem.find("a fisheye or panoramic lens, motion-blurred positions, or a "
                             "position pass not in world space; give --camera or --fov"),
            std::string::npos)
      << fit.problem;
}

TEST(CameraFitTest, FlatWallFacingTheCameraIsRefused) {
  // A plane's image fixes a homography (8 numbers), not a camera (10): the focal length trades
  // against the wall's distance. Refused, whatever its tilt.
  const Camera want = KnownCamera(280, 280, 160, 90, true);
  for (double tilt : {0.0, 0.004}) {
    const CameraFitResult fit =
        Fit(Render(want, 320, 180, [&](double px, double) { return 4.0 / (1 + tilt * px / 100); }));
    ASSERT_FALSE(fit.ok) << tilt;
    EXPECT_NE(fit.problem.find("its surfaces lie on one plane"), std::string::npos) << fit.problem;
    EXPECT_NE(fit.problem.find("give --camera or --fov"), std::string::npos) << fit.problem;
  }
}

TEST(CameraFitTest, SkewIsRefused) {
  // px = cx + (fx x + s y) / z: a sheared image the library's cameras cannot represent. With
  // s = 4 px per unit y/z the top and bottom rows shift by 1.3 px, which a camera without skew
  // cannot take up within half a pixel (its residual is 0.64 px) and one with skew fits
  // exactly: refused as skew, not as a lens that is no pinhole.
  const Camera want = KnownCamera(280, 280, 160, 90, true);
  const double s = 4;
  const auto sheared = [&](double px, double py, double z) {
    const double y = (want.cy - py) * z / want.fy;
    return Imath::V3d((px - want.cx - s * y / z) * z / want.fx, y, z);
  };
  const CameraFitResult fit = Fit(Render(want, 320, 180, Hills, sheared));
  ASSERT_FALSE(fit.ok);
  EXPECT_NE(fit.problem.find("skew"), std::string::npos) << fit.problem;
}

TEST(CameraFitTest, TooFewSurfacePixelsAreRefused) {
  // Surface only in a 20 x 20 px corner: 16 lattice points, fewer than the 50 needed.
  const Camera want = KnownCamera(280, 280, 160, 90, true);
  const CameraFitResult fit = Fit(Render(want, 320, 180, [](double px, double py) {
    return px < 20 && py < 20 ? Hills(px, py) : std::numeric_limits<double>::infinity();
  }));
  ASSERT_FALSE(fit.ok);
  EXPECT_NE(fit.problem.find("too few surface pixels away from edges"), std::string::npos)
      << fit.problem;
}

// A deterministic uniform number in [-1, 1) per pixel and channel.
double Noise(int x, int y, int k) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 73856093u ^
                    static_cast<std::uint32_t>(y) * 19349663u ^
                    static_cast<std::uint32_t>(k + 1) * 83492791u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return h / 2147483648.0 - 1;
}

TEST(CameraFitTest, NoisyPositionsAndFilteredSilhouettesStillFit) {
  // A box 2 m in front of the hills, its silhouette's positions blended half and half with the
  // surface behind (what a pixel filter does; the depth pass keeps one sample), and every
  // position moved by up to 0.1 px across the view and 1 mm along it.
  const Camera want = KnownCamera(280, 280, 170, 85, true);
  const auto depth = [](double px, double py) {
    const bool box = px > 100 && px < 200 && py > 40 && py < 120;
    return box ? Hills(px, py) - 2.0 : Hills(px, py);
  };
  Passes p = Render(want, 320, 180, depth);
  const Imath::M44d camera_to_world = want.world_to_camera.inverse();
  const Imath::M44d world_to_camera = want.world_to_camera;
  Image filtered = p.position;
  for (int y = 1; y + 1 < 180; ++y) {
    for (int x = 1; x + 1 < 320; ++x) {
      const double z = p.distance.at(0, x, y);
      for (int k = 0; k < 3; ++k) {
        const float left = p.position.at(k, x - 1, y), up = p.position.at(k, x, y - 1);
        if (std::fabs(p.distance.at(0, x - 1, y) - z) > 1)
          filtered.at(k, x, y) = 0.5f * (filtered.at(k, x, y) + left);
        else if (std::fabs(p.distance.at(0, x, y - 1) - z) > 1)
          filtered.at(k, x, y) = 0.5f * (filtered.at(k, x, y) + up);
      }
      Imath::V3d c = Imath::V3d(filtered.at(0, x, y), filtered.at(1, x, y), filtered.at(2, x, y)) *
                     world_to_camera;
      const double px_m = 0.1 * c.z / want.fx;  // 0.1 px at this depth
      c += Imath::V3d(Noise(x, y, 0) * px_m, Noise(x, y, 1) * px_m, Noise(x, y, 2) * 1e-3);
      const Imath::V3d w = c * camera_to_world;
      for (int k = 0; k < 3; ++k) filtered.at(k, x, y) = static_cast<float>(w[k]);
    }
  }
  p.position = filtered;
  const CameraFitResult fit = Fit(p);
  ASSERT_TRUE(fit.ok) << fit.problem;
  // Uniform noise of +-0.1 px on each axis: RMS 0.1 * sqrt(2/3) = 0.082 px.
  EXPECT_NEAR(fit.residual_px, 0.082, 0.01);
  EXPECT_NEAR(fit.camera.fx, want.fx, 1e-3 * want.fx);
  EXPECT_NEAR(fit.camera.fy, want.fy, 1e-3 * want.fy);
  EXPECT_NEAR(fit.camera.cx, want.cx, 1e-3 * want.cx);
  EXPECT_NEAR(fit.camera.cy, want.cy, 1e-3 * want.cy);
  EXPECT_NEAR(fit.camera.hfov_deg(320), want.hfov_deg(320), 0.01);
}

TEST(CameraFitTest, ReprojectionErrorMeasuresAnotherCamera) {
  // The disagreement check: the same pose with the principal point 2 px to the right.
  const Camera want = KnownCamera(280, 280, 160, 90, true);
  const Passes p = Render(want, 320, 180, Hills);
  std::size_t lattice = 0;
  const std::vector<PositionSample> samples =
      position_samples(p.position, p.distance, p.window, p.window, &lattice);
  EXPECT_LT(reprojection_rms_px(want, samples, p.window), 1e-4);
  Camera shifted = want;
  shifted.cx += 2;
  EXPECT_NEAR(reprojection_rms_px(shifted, samples, p.window), 2.0, 1e-4);
}

}  // namespace
}  // namespace ssgi::detail
