// Tests of the camera module: matrix maths, projection, cameras from --fov, from header
// matrices (OpenEXR, Nuke, V-Ray, Arnold conventions) and from sidecars, and the sample data's
// cameras against its Position and Depth passes.
#include "ssgi/camera.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "io/camera.h"
#include "io/camera_header.h"
#include "ssgi/error.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// Runs `call`, expecting Error of `kind` whose message contains `needle`.
template <typename Call>
void ExpectError(const Call& call, ErrorKind kind, const std::string& needle) {
  SCOPED_TRACE(needle);
  try {
    call();
    ADD_FAILURE() << "no error thrown";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), kind) << error.what();
    EXPECT_NE(std::string(error.what()).find(needle), std::string::npos) << error.what();
  }
}

Imath::M44d Diagonal(double x, double y, double z) {
  Imath::M44d d;
  d[0][0] = x;
  d[1][1] = y;
  d[2][2] = z;
  return d;
}

Imath::M44d Translation(double x, double y, double z) {
  Imath::M44d t;
  t[3][0] = x;
  t[3][1] = y;
  t[3][2] = z;
  return t;
}

// Rotation by `deg` about a unit axis, row-vector convention (p' = p * R).
Imath::M44d Rotation(Imath::V3d axis, double deg) {
  const double a = deg * kPi / 180, c = std::cos(a), s = std::sin(a), t = 1 - c;
  const double x = axis.x, y = axis.y, z = axis.z;
  Imath::M44d r;
  // Column-vector rotation matrix, transposed into row-vector form.
  const double col[3][3] = {{t * x * x + c, t * x * y - s * z, t * x * z + s * y},
                            {t * x * y + s * z, t * y * y + c, t * y * z - s * x},
                            {t * x * z - s * y, t * y * z + s * x, t * z * z + c}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i][j] = col[j][i];
  return r;
}

// Camera space (x right, y up, +z forward) to NDC for pinhole intrinsics in pixels over a
// W x H display window: NDC x = (fx x / z + cx) / W, NDC y = (cy - fy y / z) / H, w = z.
Imath::M44d CameraToNdc(double fx, double fy, double cx, double cy, int w, int h) {
  Imath::M44d p;
  p[0][0] = fx / w;
  p[1][1] = -fy / h;
  p[2][0] = cx / w;
  p[2][1] = cy / h;
  p[2][2] = 1;
  p[2][3] = 1;
  p[3][2] = -0.1;  // NDC z is unused; a near-plane term as renderers write it
  p[3][3] = 0;
  return p;
}

double MaxAbsDiff(const Imath::M44d& a, const Imath::M44d& b) {
  double d = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) d = std::max(d, std::abs(a[i][j] - b[i][j]));
  return d;
}

// A camera placed away from the origin, rotated about a skew axis (nothing axis-aligned).
Imath::M44d TestWorldToCamera() {
  const double n = std::sqrt(0.3 * 0.3 + 0.8 * 0.8 + 0.5 * 0.5);
  const Imath::M44d camera_to_world =
      Rotation({0.3 / n, 0.8 / n, 0.5 / n}, 37) * Translation(2.5, -1.25, 4.0);
  return inverse_checked(camera_to_world);
}

TEST(MatrixTest, InverseRoundTrip) {
  Imath::M44d a = TestWorldToCamera() * CameraToNdc(700, 650, 400, 260, 800, 600);
  a[3][3] = 0.25;  // make it a general (invertible) matrix, not just a camera
  const Imath::M44d i = a * inverse_checked(a);
  const Imath::M44d j = inverse_checked(a) * a;
  // Double precision on entries of order 1..10: 1e-12 is ~1e4 ulps of slack.
  EXPECT_LT(MaxAbsDiff(i, Imath::M44d()), 1e-12);
  EXPECT_LT(MaxAbsDiff(j, Imath::M44d()), 1e-12);
}

TEST(MatrixTest, ProductAppliesLeftFirst) {
  const Imath::M44d a = Rotation({0, 0, 1}, 90), b = Translation(1, 2, 3);
  const Imath::V3d p{1, 0, 0};
  const Imath::V3d q = p * (a * b);
  // Rotating (1,0,0) by 90 degrees about z gives (0,1,0); then the translation.
  EXPECT_NEAR(q.x, 1, 1e-15);
  EXPECT_NEAR(q.y, 3, 1e-15);
  EXPECT_NEAR(q.z, 3, 1e-15);
  Imath::V3d d(0);
  (a * b).multDirMatrix(p, d);  // directions ignore translation
  EXPECT_NEAR(d.x, 0, 1e-15);
  EXPECT_NEAR(d.y, 1, 1e-15);
  EXPECT_NEAR(d.z, 0, 1e-15);
}

TEST(MatrixTest, SingularThrowsInput) {
  Imath::M44d a = TestWorldToCamera();
  for (int j = 0; j < 4; ++j) a[2][j] = 2 * a[0][j];  // two parallel rows
  ExpectError([&] { inverse_checked(a); }, ErrorKind::kInput, "singular");
  Imath::M44d zero = Diagonal(0, 0, 0);
  zero[3][3] = 0;
  ExpectError([&] { inverse_checked(zero); }, ErrorKind::kInput, "singular");
  Imath::M44d nan = Imath::M44d();
  nan[1][2] = std::nan("");
  ExpectError([&] { inverse_checked(nan); }, ErrorKind::kInput, "non-finite");
}

TEST(MatrixTest, SmallScaleIsNotSingular) {
  // The test is relative, so a camera in micrometres or light years inverts fine.
  const Imath::M44d tiny = Diagonal(1e-6, 1e-6, 1e-6) * Translation(3e-6, 0, 1e-6);
  EXPECT_LT(MaxAbsDiff(tiny * inverse_checked(tiny), Imath::M44d()), 1e-12);
  const Imath::M44d huge = Translation(1e9, -2e9, 5e8);
  EXPECT_LT(MaxAbsDiff(huge * inverse_checked(huge), Imath::M44d()), 1e-6);
}

TEST(CameraFromFovTest, HfovRoundTrip) {
  const Box2i display{0, 0, 1920, 1080};
  for (double fov : {0.5, 30.0, 83.9744, 120.0, 179.0}) {
    const Camera c = camera_from_fov(fov, display);
    EXPECT_NEAR(c.hfov_deg(display.width()), fov, 1e-9 * fov);
    EXPECT_DOUBLE_EQ(c.fx, c.fy);
    EXPECT_DOUBLE_EQ(c.cx, 960);
    EXPECT_DOUBLE_EQ(c.cy, 540);
    EXPECT_FALSE(c.has_world_transform);
    EXPECT_EQ(c.source, "--fov");
  }
}

TEST(CameraFromFovTest, PixelAspectScalesFy) {
  // 2:1 anamorphic pixels: each pixel spans twice the angle across as down, so 1/fx = 2/fy.
  const Box2i display{0, 0, 1000, 800};
  const Camera c = camera_from_fov(60, display, 2.0);
  EXPECT_DOUBLE_EQ(c.fy, 2 * c.fx);
  // Displayed, the image is 2000 x 800 square units: the vertical fov is that of a
  // 1000 x 400 square-pixel image with the same hfov.
  const double vfov = 2 * std::atan(400 / c.fy) * 180 / kPi;
  EXPECT_NEAR(vfov, 2 * std::atan(std::tan(30 * kPi / 180) * 400 / 1000) * 180 / kPi, 1e-9);
}

TEST(CameraFromFovTest, RejectsBadValues) {
  const Box2i display{0, 0, 64, 64};
  ExpectError([&] { camera_from_fov(0, display); }, ErrorKind::kUsage, "outside (0, 180)");
  ExpectError([&] { camera_from_fov(180, display); }, ErrorKind::kUsage, "outside (0, 180)");
  ExpectError([&] { camera_from_fov(std::nan(""), display); }, ErrorKind::kUsage, "outside");
  ExpectError([&] { camera_from_fov(40, display, 0); }, ErrorKind::kUsage, "pixel aspect");
  ExpectError([&] { camera_from_fov(40, Box2i{}); }, ErrorKind::kInput, "empty display");
}

TEST(CameraTest, UnprojectProjectRoundTrip) {
  const Camera c = camera_from_matrices(
      TestWorldToCamera(), TestWorldToCamera() * CameraToNdc(700, 650, 410, 250, 800, 600),
      Box2i{0, 0, 800, 600}, "t.exr");
  for (double py : {0.5, 123.25, 599.5})
    for (double px : {0.5, 401.75, 799.5})
      for (double z : {1e-4, 1.0, 37.5, 1e10}) {
        const Imath::V3d p = c.unproject(px, py, z);
        EXPECT_DOUBLE_EQ(p.z, z);
        double qx, qy;
        c.project(p, &qx, &qy);
        EXPECT_NEAR(qx, px, 1e-9);
        EXPECT_NEAR(qy, py, 1e-9);
        const Imath::V3d d = c.view_dir(px, py);
        EXPECT_NEAR(d.x * d.x + d.y * d.y + d.z * d.z, 1, 1e-15);
        EXPECT_NEAR(d.x / d.z, p.x / p.z, 1e-12);  // along the same ray
        EXPECT_NEAR(d.y / d.z, p.y / p.z, 1e-12);
      }
}

TEST(CameraFromMatricesTest, ProjectsKnownPointOffCentre) {
  // An off-centre camera (principal point 90 px right of and 40 px above the centre, as a
  // lens shift or screenWindowCenter gives), rotated about a skew axis, away from the origin.
  const int w = 800, h = 600;
  const double fx = 700, fy = 650, cx = 490, cy = 260;
  const Imath::M44d w2c = TestWorldToCamera();
  const Imath::M44d w2ndc = w2c * CameraToNdc(fx, fy, cx, cy, w, h);
  const Camera c = camera_from_matrices(w2c, w2ndc, Box2i{0, 0, w, h}, "shifted.exr");
  EXPECT_NEAR(c.fx, fx, 1e-9);
  EXPECT_NEAR(c.fy, fy, 1e-9);
  EXPECT_NEAR(c.cx, cx, 1e-9);
  EXPECT_NEAR(c.cy, cy, 1e-9);
  EXPECT_TRUE(c.has_world_transform);

  // A world point that lands at a known pixel: unproject that pixel with the intrinsics.
  const double want_x = 123.4, want_y = 456.7, depth = 7.5;
  const Imath::V3d p_cam{(want_x - cx) / fx * depth, (cy - want_y) / fy * depth, depth};
  const Imath::V3d p_world = p_cam * inverse_checked(w2c);
  double px, py;
  c.project(p_world * c.world_to_camera, &px, &py);
  EXPECT_NEAR(px, want_x, 1e-4);
  EXPECT_NEAR(py, want_y, 1e-4);
  // The matrices themselves agree: pixel = NDC * (W, H).
  const Imath::V3d ndc = p_world * w2ndc;
  EXPECT_NEAR(ndc.x * w, want_x, 1e-4);
  EXPECT_NEAR(ndc.y * h, want_y, 1e-4);
  // hfov over the shifted window: the two half-angles differ.
  EXPECT_NEAR(c.hfov_deg(w), (std::atan(cx / fx) + std::atan((w - cx) / fx)) * 180 / kPi, 1e-12);
}

TEST(CameraFromMatricesTest, NormalisesOpenGlAndLeftHandedCameraSpaces) {
  // The same camera written with -z forward (OpenGL, Arnold, Blender) or x pointing left
  // (OpenEXR's own text): the result must be the same camera and the same pixels.
  const int w = 640, h = 480;
  const Imath::M44d w2c = TestWorldToCamera();
  const Imath::M44d w2ndc = w2c * CameraToNdc(500, 500, 300, 250, w, h);
  const Camera ref = camera_from_matrices(w2c, w2ndc, Box2i{0, 0, w, h}, "ref.exr");
  for (const Imath::M44d& flip : {Diagonal(1, 1, -1), Diagonal(-1, 1, 1), Diagonal(-1, -1, -1)}) {
    const Camera c = camera_from_matrices(w2c * flip, w2ndc, Box2i{0, 0, w, h}, "flip.exr");
    EXPECT_NEAR(c.fx, ref.fx, 1e-9);
    EXPECT_NEAR(c.fy, ref.fy, 1e-9);
    EXPECT_NEAR(c.cx, ref.cx, 1e-9);
    EXPECT_NEAR(c.cy, ref.cy, 1e-9);
    EXPECT_LT(MaxAbsDiff(c.world_to_camera, ref.world_to_camera), 1e-12);
  }
}

TEST(CameraFromMatricesTest, RejectsNonPerspective) {
  const Box2i display{0, 0, 320, 180};
  const Imath::M44d w2c = TestWorldToCamera();
  // Orthographic: NDC = affine function of camera x, y; w = 1.
  Imath::M44d ortho;
  ortho[0][0] = 0.1;
  ortho[1][1] = -0.1;
  ortho[3][0] = 0.5;
  ortho[3][1] = 0.5;
  ExpectError([&] { camera_from_matrices(w2c, w2c * ortho, display, "ortho.exr"); },
              ErrorKind::kInput, "not a perspective projection");
  // All zeros.
  Imath::M44d zero = Diagonal(0, 0, 0);
  zero[3][3] = 0;
  ExpectError([&] { camera_from_matrices(w2c, zero, display, "zero.exr"); }, ErrorKind::kInput,
              "not a perspective projection");
  // Singular worldToCamera, named with the file.
  try {
    camera_from_matrices(Diagonal(1, 1, 0), w2c, display, "sing.exr");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
    EXPECT_EQ(e.file(), "sing.exr");
  }
  // Skewed image plane.
  Imath::M44d skew = CameraToNdc(300, 300, 160, 90, 320, 180);
  skew[1][0] = 0.2;
  ExpectError([&] { camera_from_matrices(w2c, w2c * skew, display, "skew.exr"); },
              ErrorKind::kInput, "skew");
  // Centre of projection 1 unit behind the camera: w = z + 1.
  Imath::M44d moved = CameraToNdc(300, 300, 160, 90, 320, 180);
  moved[3][3] = 1;
  ExpectError([&] { camera_from_matrices(w2c, w2c * moved, display, "moved.exr"); },
              ErrorKind::kInput, "centre of projection");
  // A -1..1 screen matrix under the name worldToNDC (3Delight's header in
  // johannesvollmer/exrs#83: 30 degrees, 2048 x 2048).
  Imath::M44d screen;
  screen[0][0] = screen[1][1] = 3.73205;
  screen[2][3] = 1;
  screen[3][2] = -0.001;
  screen[3][3] = 0;
  ExpectError([&] { camera_from_matrices(Imath::M44d(), screen, display, "3dl.exr"); },
              ErrorKind::kInput, "screen-space");
  // Non-finite entries.
  Imath::M44d inf = w2c * CameraToNdc(300, 300, 160, 90, 320, 180);
  inf[2][0] = INFINITY;
  ExpectError([&] { camera_from_matrices(w2c, inf, display, "inf.exr"); }, ErrorKind::kInput,
              "non-finite");
}

void SetMatrix(OIIO::ImageSpec* spec, const std::string& name, const Imath::M44d& m) {
  float f[16];
  for (int i = 0; i < 16; ++i) f[i] = static_cast<float>(m[i / 4][i % 4]);
  spec->attribute(name, OIIO::TypeMatrix44, f);
}

OIIO::ImageSpec SpecOf(int w, int h) { return OIIO::ImageSpec(w, h, 3, OIIO::TypeFloat); }

// Pixel of a world point through a camera.
void PixelOf(const Camera& c, const Imath::V3d& world, double* px, double* py) {
  c.project(world * c.world_to_camera, px, py);
}

TEST(CameraFromHeaderTest, NoCameraAttributesGivesNullopt) {
  EXPECT_FALSE(detail::camera_from_header(SpecOf(64, 32), Box2i{0, 0, 64, 32}, "a.exr"));
  // worldToCamera alone (no projection, no lens) is not a camera either.
  OIIO::ImageSpec spec = SpecOf(64, 32);
  SetMatrix(&spec, "worldToCamera", TestWorldToCamera());
  EXPECT_FALSE(detail::camera_from_header(spec, Box2i{0, 0, 64, 32}, "a.exr"));
}

TEST(CameraFromHeaderTest, StandardAndNukeNamesAgree) {
  const int w = 320, h = 180;
  const Box2i display{0, 0, w, h};
  const Imath::M44d w2c = TestWorldToCamera();
  const Imath::M44d w2ndc = w2c * CameraToNdc(200, 200, 170, 80, w, h);
  const Camera ref = camera_from_matrices(w2c, w2ndc, display, "ref");
  for (const std::string prefix : {"", "exr/"}) {
    OIIO::ImageSpec spec = SpecOf(w, h);
    SetMatrix(&spec, prefix + "worldToCamera", w2c);
    SetMatrix(&spec, prefix + "worldToNDC", w2ndc);
    const std::optional<Camera> c = detail::camera_from_header(spec, display, "a.exr");
    ASSERT_TRUE(c);
    // Float-stored matrices: ~1e-7 relative, i.e. ~2e-5 px on a 200 px focal length.
    EXPECT_NEAR(c->fx, ref.fx, 1e-4);
    EXPECT_NEAR(c->cx, ref.cx, 1e-4);
    EXPECT_NEAR(c->cy, ref.cy, 1e-4);
    EXPECT_EQ(c->source, "header worldToCamera/worldToNDC");
  }
}

TEST(CameraFromHeaderTest, WorldToScreenUsesScreenWindow) {
  // RenderMan-style screen space for a 2:1 image with a shifted screen window, written with
  // OpenEXR's screenWindowCenter/Width and a pixel aspect of 1.5.
  const int w = 400, h = 300;
  const double pa = 1.5, sw = 2.0, scx = 0.2, scy = -0.1;
  const double sh = sw * h / (w * pa);  // OpenEXR: height from width, display window, aspect
  const Imath::M44d w2c = TestWorldToCamera();
  Imath::M44d cam_to_screen;  // screen = (x/z, y/z): the z = 1 plane
  cam_to_screen[2][3] = 1;
  cam_to_screen[3][3] = 0;
  OIIO::ImageSpec spec = SpecOf(w, h);
  SetMatrix(&spec, "worldToCamera", w2c);
  SetMatrix(&spec, "worldToScreen", w2c * cam_to_screen);
  const float center[2] = {static_cast<float>(scx), static_cast<float>(scy)};
  spec.attribute("screenWindowCenter", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::VEC2),
                 center);
  spec.attribute("screenWindowWidth", static_cast<float>(sw));
  spec.attribute("PixelAspectRatio", static_cast<float>(pa));
  const std::optional<Camera> c = detail::camera_from_header(spec, Box2i{0, 0, w, h}, "s.exr");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->source, "header worldToCamera/worldToScreen");
  // Screen window [scx - sw/2, scx + sw/2] covers the width: fx = W / sw, and the optical
  // axis (screen 0) sits at (0 - (scx - sw/2)) / sw of the width.
  EXPECT_NEAR(c->fx, w / sw, 1e-4);
  EXPECT_NEAR(c->fy, h / sh, 1e-4);
  EXPECT_NEAR(c->fy, c->fx * pa, 1e-4);
  EXPECT_NEAR(c->cx, (sw / 2 - scx) / sw * w, 1e-4);
  EXPECT_NEAR(c->cy, (scy + sh / 2) / sh * h, 1e-4);
}

TEST(CameraFromHeaderTest, VRayCameraTransformAndFov) {
  const int w = 300, h = 200;
  const Box2i display{0, 0, w, h};
  // Camera at (1, 2, 3). 3ds Max frame: identity rotation looks down -Z, +Y up.
  OIIO::ImageSpec spec = SpecOf(w, h);
  SetMatrix(&spec, "worldtocamera", Translation(1, 2, 3));  // OIIO's name for cameraTransform
  spec.attribute("cameraFov", 60.0f);
  spec.attribute("cameraProjection", 0);
  std::optional<Camera> c = detail::camera_from_header(spec, display, "max.exr");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->source, "header V-Ray cameraTransform/cameraFov");
  EXPECT_NEAR(c->hfov_deg(w), 60, 1e-9);
  double px, py;
  PixelOf(*c, {1, 2, -7}, &px, &py);  // 10 ahead
  EXPECT_NEAR(px, w / 2.0, 1e-9);
  EXPECT_NEAR(py, h / 2.0, 1e-9);
  PixelOf(*c, {1, 3, -7}, &px, &py);  // above
  EXPECT_LT(py, h / 2.0);
  PixelOf(*c, {2, 2, -7}, &px, &py);  // right
  EXPECT_GT(px, w / 2.0);

  // V-Ray for Maya frame: -Y forward, -Z up; written with the translation in the last column.
  Imath::M44d column_form = Imath::M44d();
  column_form[0][3] = 1;
  column_form[1][3] = 2;
  column_form[2][3] = 3;
  OIIO::ImageSpec maya = SpecOf(w, h);
  SetMatrix(&maya, "cameraTransform", column_form);
  maya.attribute("cameraFov", 60.0f);
  maya.attribute("vrayInfo/vrayversion", "Version of V-Ray for Maya 3.60.02");
  c = detail::camera_from_header(maya, display, "maya.exr");
  ASSERT_TRUE(c);
  PixelOf(*c, {1, -8, 3}, &px, &py);  // 10 along -Y
  EXPECT_NEAR(px, w / 2.0, 1e-9);
  EXPECT_NEAR(py, h / 2.0, 1e-9);
  PixelOf(*c, {1, -8, 2}, &px, &py);  // towards -Z: up
  EXPECT_LT(py, h / 2.0);
  PixelOf(*c, {2, -8, 3}, &px, &py);  // +X: right
  EXPECT_GT(px, w / 2.0);

  // Only the rendered fov is reliable; a non-perspective projection is an error.
  OIIO::ImageSpec ortho = spec;
  ortho.attribute("cameraProjection", 1);
  ExpectError([&] { detail::camera_from_header(ortho, display, "o.exr"); }, ErrorKind::kInput,
              "cameraProjection");
}

TEST(CameraFromHeaderTest, ArnoldLensAttributes) {
  const int w = 200, h = 100;
  const Box2i display{0, 0, w, h};
  OIIO::ImageSpec spec = SpecOf(w, h);
  SetMatrix(&spec, "worldToCamera", Translation(0, 0, -5));  // camera at z = 5, looking down -z
  spec.attribute("CameraFocalLength", 35.0f);
  spec.attribute("CameraFilmApertureHorizontal", 36.0f);
  const std::optional<Camera> c = detail::camera_from_header(spec, display, "ai.exr");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->source, "header Arnold worldToCamera/CameraFov");
  EXPECT_NEAR(c->hfov_deg(w), 2 * std::atan(18.0 / 35) * 180 / kPi, 1e-9);
  double px, py;
  PixelOf(*c, {0, 0, 0}, &px, &py);
  EXPECT_NEAR(px, w / 2.0, 1e-9);
  EXPECT_NEAR(py, h / 2.0, 1e-9);
  EXPECT_GT((Imath::V3d(0) * c->world_to_camera).z, 0);
  // CameraFov, when written, wins over focal length and aperture.
  spec.attribute("CameraFov", 50.0f);
  EXPECT_NEAR(detail::camera_from_header(spec, display, "ai.exr")->hfov_deg(w), 50, 1e-5);
}

class SidecarTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("ssgi_camera_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }

  fs::path dir_;
  const Box2i display_{0, 0, 320, 180};
};

TEST_F(SidecarTest, PerFrameFovAndStaticFallback) {
  const std::string path =
      Write("cam.json",
            R"({"frames": [{"frame": 1, "hfov_deg": 40}, {"frame": 2, "hfov_deg": 50,
                     "pixel_aspect": 2}],
          "hfov_deg": 70})");
  const Camera c1 = detail::camera_from_sidecar(path, 1, display_);
  EXPECT_NEAR(c1.hfov_deg(320), 40, 1e-9);
  EXPECT_EQ(c1.source, "sidecar " + path);
  EXPECT_FALSE(c1.has_world_transform);
  const Camera c2 = detail::camera_from_sidecar(path, 2, display_);
  EXPECT_NEAR(c2.hfov_deg(320), 50, 1e-9);
  EXPECT_DOUBLE_EQ(c2.fy, 2 * c2.fx);
  // Frame 7 is not listed: the static camera applies.
  EXPECT_NEAR(detail::camera_from_sidecar(path, 7, display_).hfov_deg(320), 70, 1e-9);
}

TEST_F(SidecarTest, StaticMatricesAndFovWithTransform) {
  const Imath::M44d w2c = TestWorldToCamera();
  const Imath::M44d ndc = w2c * CameraToNdc(200, 200, 150, 95, 320, 180);
  auto flat = [](const Imath::M44d& m) {
    std::string s = "[";
    for (int i = 0; i < 16; ++i) {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", m[i / 4][i % 4]);
      s += (i ? "," : "") + std::string(buf);
    }
    return s + "]";
  };
  const std::string matrices =
      Write("m.json", "{\"worldToCamera\": " + flat(w2c) + ", \"worldToNDC\": " + flat(ndc) + "}");
  const Camera c = detail::camera_from_sidecar(matrices, 12, display_);
  EXPECT_NEAR(c.fx, 200, 1e-9);
  EXPECT_NEAR(c.cx, 150, 1e-9);
  EXPECT_NEAR(c.cy, 95, 1e-9);
  EXPECT_TRUE(c.has_world_transform);

  const std::string fov_and_pose = Write(
      "f.json",
      "{\"frames\": [{\"frame\": 3, \"hfov_deg\": 45, \"worldToCamera\": " + flat(w2c) + "}]}");
  const Camera f = detail::camera_from_sidecar(fov_and_pose, 3, display_);
  EXPECT_NEAR(f.hfov_deg(320), 45, 1e-9);
  EXPECT_TRUE(f.has_world_transform);
  EXPECT_LT(MaxAbsDiff(f.world_to_camera, w2c), 1e-15);
}

TEST_F(SidecarTest, Errors) {
  const std::string missing = (dir_ / "nope.json").string();
  ExpectError([&] { detail::camera_from_sidecar(missing, 1, display_); }, ErrorKind::kIO,
              "cannot open");
  const std::string bad = Write("bad.json", "{\"frames\": [");
  ExpectError([&] { detail::camera_from_sidecar(bad, 1, display_); }, ErrorKind::kInput,
              "not valid JSON");
  const std::string no_frame = Write("nf.json", R"({"frames": [{"frame": 1, "hfov_deg": 40}]})");
  try {
    detail::camera_from_sidecar(no_frame, 2, display_);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
    EXPECT_EQ(e.file(), no_frame);  // the CLI prints "ssgi: error: <file>: ..."
    EXPECT_NE(std::string(e.what()).find("no camera for frame 2"), std::string::npos);
  }
  const std::string bad_fov = Write("bf.json", R"({"frames": [{"frame": 1, "hfov_deg": 190}]})");
  ExpectError([&] { detail::camera_from_sidecar(bad_fov, 1, display_); }, ErrorKind::kInput,
              "hfov_deg");
  const std::string half =
      Write("h.json", R"({"worldToNDC": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]})");
  ExpectError([&] { detail::camera_from_sidecar(half, 1, display_); }, ErrorKind::kInput,
              "come together");
  const std::string short_matrix =
      Write("s.json", R"({"worldToCamera": [1,0,0], "worldToNDC": [1,0,0]})");
  ExpectError([&] { detail::camera_from_sidecar(short_matrix, 1, display_); }, ErrorKind::kInput,
              "16 numbers");
  const std::string no_int = Write("ni.json", R"({"frames": [{"frame": "one"}]})");
  ExpectError([&] { detail::camera_from_sidecar(no_int, 1, display_); }, ErrorKind::kInput,
              "integer \"frame\"");
}

const fs::path kRoom = fs::path(SSGI_SHARED_DATA_DIR) / "room";

// The named channels of an EXR as planes, or an empty vector when one is missing.
std::vector<std::vector<float>> ReadChannels(const std::string& path,
                                             const std::vector<std::string>& names,
                                             OIIO::ImageSpec* spec_out) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return {};
  const OIIO::ImageSpec spec = in->spec();
  std::vector<float> all(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, all.data())) return {};
  std::vector<std::vector<float>> planes;
  for (const std::string& name : names) {
    const auto it = std::find(spec.channelnames.begin(), spec.channelnames.end(), name);
    if (it == spec.channelnames.end()) return {};
    const std::size_t c = it - spec.channelnames.begin();
    std::vector<float> plane(static_cast<std::size_t>(spec.width) * spec.height);
    for (std::size_t i = 0; i < plane.size(); ++i) plane[i] = all[i * spec.nchannels + c];
    planes.push_back(std::move(plane));
  }
  *spec_out = spec;
  return planes;
}

Box2i DisplayOf(const OIIO::ImageSpec& spec) {
  return {spec.full_x, spec.full_y, spec.full_x + spec.full_width, spec.full_y + spec.full_height};
}

// Every frame of both sample shots: the header camera must put each surface pixel's Position
// (world space) back on that pixel's centre, and its camera-space z must be the Depth pass.
TEST(SampleDataTest, HeaderCameraMatchesPositionAndDepth) {
  if (!fs::exists(kRoom)) GTEST_SKIP() << kRoom << " not present";
  for (const std::string scene : {"room", "stage"}) {
    for (int frame = 1; frame <= 6; ++frame) {
      char name[32];
      std::snprintf(name, sizeof name, "%s.%04d.exr", scene.c_str(), frame);
      const std::string path = (kRoom.parent_path() / scene / name).string();
      SCOPED_TRACE(path);
      OIIO::ImageSpec spec;
      const auto planes = ReadChannels(path,
                                       {"ViewLayer.Position.X", "ViewLayer.Position.Y",
                                        "ViewLayer.Position.Z", "ViewLayer.Depth.Z"},
                                       &spec);
      ASSERT_EQ(planes.size(), 4u);
      const Box2i display = DisplayOf(spec);
      const std::optional<Camera> c = detail::camera_from_header(spec, display, path);
      ASSERT_TRUE(c);
      EXPECT_EQ(c->source, "header worldToCamera/worldToNDC");
      if (scene == "room") {
        // camera.json: hfov_deg 83.97442499163331 (20 mm lens, 36 mm sensor).
        EXPECT_NEAR(c->hfov_deg(display.width()), 83.97442499163331, 0.01);
      }

      std::vector<double> dx, dy, depth_rel;
      double mean_x = 0, mean_y = 0;
      for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * spec.width + x;
          const double depth = planes[3][i];
          if (!(depth < 1e9)) continue;  // background: 1e10
          const Imath::V3d p =
              Imath::V3d(planes[0][i], planes[1][i], planes[2][i]) * c->world_to_camera;
          double px, py;
          c->project(p, &px, &py);
          dx.push_back(px - (x + 0.5));
          dy.push_back(py - (y + 0.5));
          mean_x += dx.back();
          mean_y += dy.back();
          depth_rel.push_back(std::abs(p.z - depth) / depth);
        }
      const std::size_t n = dx.size();
      ASSERT_GT(n, 50000u);  // nearly all of the 57600 pixels are surface
      mean_x /= n;
      mean_y /= n;
      double max_err = 0, max_residual = 0;
      for (std::size_t k = 0; k < n; ++k) {
        max_err = std::max(max_err, std::hypot(dx[k], dy[k]));
        max_residual = std::max(max_residual, std::hypot(dx[k] - mean_x, dy[k] - mean_y));
      }
      const double max_depth = *std::max_element(depth_rel.begin(), depth_rel.end());
      std::printf(
          "[ %s ] %zu px: reprojection max %.2e px, mean offset (%+.2e, %+.2e) px, "
          "max about the mean %.2e px; max |Depth.Z - z| / Depth.Z %.1e\n",
          name, n, max_err, mean_x, mean_y, max_residual, max_depth);
      // Cycles' Position (and Depth) are one sample per pixel, not pixel-filtered like Normal:
      // the first sample sits a constant ~7.5e-4 px from the centre, (+5.3e-4, -5.3e-4) px on
      // every frame. So the issue's 1e-3 px holds for every surface pixel, edges included
      // (measured max 9.3e-4 px over both shots). About that offset the scatter is float
      // rounding of positions and matrices (measured <= 3.0e-4 px).
      EXPECT_LT(max_err, 1e-3);
      EXPECT_LT(max_residual, 5e-4);
      // Planar depth is camera-space z to float precision (measured <= 2.6e-7 relative).
      EXPECT_LT(max_depth, 1e-6);
    }
  }
}

TEST(SampleDataTest, SidecarMatchesHeaderForEveryFrame) {
  const std::string json = (kRoom / "camera.json").string();
  if (!fs::exists(json)) GTEST_SKIP() << json << " not present";
  for (int frame = 1; frame <= 6; ++frame) {
    SCOPED_TRACE(frame);
    char name[32];
    std::snprintf(name, sizeof name, "room.%04d.exr", frame);
    auto in = OIIO::ImageInput::open((kRoom / name).string());
    ASSERT_TRUE(in);
    const OIIO::ImageSpec spec = in->spec();
    const Box2i display = DisplayOf(spec);
    const std::optional<Camera> header = detail::camera_from_header(spec, display, name);
    ASSERT_TRUE(header);
    const Camera sidecar = detail::camera_from_sidecar(json, frame, display);
    EXPECT_EQ(sidecar.source, "sidecar " + json);
    // The header stores the sidecar's doubles as float: ~6e-8 relative per entry, so compare
    // relatively (1e-6) rather than in absolute pixels (fx ~ 144 px: 1e-6 relative = 1.4e-4 px).
    auto rel = [](double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); };
    EXPECT_LT(rel(header->fx, sidecar.fx), 1e-6);
    EXPECT_LT(rel(header->fy, sidecar.fy), 1e-6);
    EXPECT_LT(rel(header->cx, sidecar.cx), 1e-6);
    EXPECT_LT(rel(header->cy, sidecar.cy), 1e-6);
    EXPECT_LT(MaxAbsDiff(header->world_to_camera, sidecar.world_to_camera), 1e-6);
    // camera.json's worldToNDC came from Blender's float32 projection (1.111111044883728 for
    // 1/0.9), so its fov is 3.4e-6 degrees off the file's exact hfov_deg.
    EXPECT_NEAR(sidecar.hfov_deg(display.width()), 83.97442499163331, 1e-5);
  }
}

}  // namespace
}  // namespace ssgi
