// The passes checked against each other: a normal pass's space told by its agreement with the
// depth's normals, and a depth pass's kind and background by the position pass, on ray-cast
// scenes whose answers are known.
#include "io/pass_agreement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "io/camera.h"
#include "io/layout.h"
#include "ssgi/camera.h"
#include "ssgi/image.h"

namespace ssgi {
namespace {

constexpr int kW = 96, kH = 64;
const Box2i kWindow{0, 0, kW, kH};

// A world plane: points p with p . n = d.
struct Plane {
  Imath::V3d n;
  double d;
};

// A camera at `eye` looking along `forward` (world space, y up), as a world transform in the
// library's camera space (x right, y up, +z forward).
Camera looking(const Imath::V3d& eye, Imath::V3d forward) {
  Camera c = camera_from_fov(70, kWindow);
  forward.normalize();
  const Imath::V3d right = Imath::V3d(0, 1, 0).cross(forward).normalized();
  const Imath::V3d up = forward.cross(right);
  Imath::M44d to_world;  // rows: the camera's axes and position in world space
  for (int j = 0; j < 3; ++j) {
    to_world[0][j] = right[j];
    to_world[1][j] = up[j];
    to_world[2][j] = forward[j];
    to_world[3][j] = eye[j];
  }
  c.world_to_camera = inverse_checked(to_world);
  c.has_world_transform = true;
  return c;
}

// What a renderer writes for a room corner seen through `camera`: planar depth (+inf where no
// plane is hit), world positions (0 where none), and the normals in world and camera space.
struct Frame {
  Image depth{kW, kH, 1}, radial{kW, kH, 1}, position{kW, kH, 3};
  Image world_normal{kW, kH, 3}, camera_normal{kW, kH, 3};
};

Frame render(const Camera& camera, const std::vector<Plane>& planes) {
  Frame f;
  const Imath::M44d to_world = inverse_checked(camera.world_to_camera);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const Imath::V3d dir_cam = camera.view_dir(x + 0.5, y + 0.5);
      Imath::V3d origin, dir;
      to_world.multVecMatrix(Imath::V3d(0), origin);
      to_world.multDirMatrix(dir_cam, dir);
      double best = std::numeric_limits<double>::infinity();
      const Plane* hit = nullptr;
      for (const Plane& p : planes) {
        const double denom = dir.dot(p.n);
        if (std::fabs(denom) < 1e-12) continue;
        const double t = (p.d - origin.dot(p.n)) / denom;
        if (t > 1e-6 && t < best) {
          best = t;
          hit = &p;
        }
      }
      const float inf = std::numeric_limits<float>::infinity();
      if (!hit) {
        f.depth.at(0, x, y) = inf;
        f.radial.at(0, x, y) = inf;
        continue;
      }
      const Imath::V3d point = origin + dir * best;
      Imath::V3d cam;
      camera.world_to_camera.multVecMatrix(point, cam);
      f.depth.at(0, x, y) = static_cast<float>(cam.z);
      f.radial.at(0, x, y) = static_cast<float>(cam.length());
      Imath::V3d n = hit->n;
      if (n.dot(dir) > 0) n = -n;  // the side the camera sees
      Imath::V3d n_cam;
      camera.world_to_camera.multDirMatrix(n, n_cam);  // a rotation: normals turn alike
      for (int c = 0; c < 3; ++c) {
        f.position.at(c, x, y) = static_cast<float>(point[c]);
        f.world_normal.at(c, x, y) = static_cast<float>(n[c]);
        f.camera_normal.at(c, x, y) = static_cast<float>(n_cam[c]);
      }
    }
  }
  return f;
}

// A floor, a back wall and a side wall.
const std::vector<Plane> kCorner = {{{0, 1, 0}, 0}, {{0, 0, 1}, 6}, {{1, 0, 0}, 2.5}};

// The camera-space pass as a camera looking down -z writes it.
Image to_gl(Image n) {
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) n.at(2, x, y) = -n.at(2, x, y);
  return n;
}

double score_of(const detail::NormalSpaceScores& s, NormalSpace space) {
  for (std::size_t i = 0; i < detail::kNormalSpaces.size(); ++i)
    if (detail::kNormalSpaces[i] == space) return s.agreeing[i];
  return std::nan("");
}

TEST(NormalSpaceTest, AutoFindsTheSpaceEachPassIsIn) {
  const Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  const Frame f = render(camera, kCorner);
  const struct {
    Image pass;
    NormalSpace space;
  } cases[] = {{f.world_normal, NormalSpace::kWorld},
               {f.camera_normal, NormalSpace::kCamera},
               {to_gl(f.camera_normal), NormalSpace::kCameraGl}};
  for (const auto& c : cases) {
    SCOPED_TRACE(normal_space_name(c.space));
    const detail::NormalSpaceScores s =
        detail::score_normal_spaces(c.pass, f.depth, camera, kWindow, kWindow);
    EXPECT_GT(s.samples, 1000u);
    EXPECT_GT(score_of(s, c.space), 0.99);
    // The floor fills half the frame and the camera is tilted by 17 degrees: a wrong space
    // keeps the floor within 18 degrees, never the walls.
    for (NormalSpace other : detail::kNormalSpaces) {
      if (other != c.space) {
        EXPECT_LT(score_of(s, other), 0.6) << normal_space_name(other);
      }
    }
    const detail::NormalSpaceChoice auto_choice =
        detail::choose_normal_space(NormalSpace::kAuto, s, true, "test");
    EXPECT_EQ(auto_choice.space, c.space);
    EXPECT_EQ(auto_choice.warning, "");
    EXPECT_NE(auto_choice.reason.find("agrees with the depth"), std::string::npos)
        << auto_choice.reason;
    // Told the right space: no word against it; told a wrong one: a warning naming the right.
    EXPECT_EQ(detail::choose_normal_space(c.space, s, true, "the layout says").warning, "");
    const NormalSpace wrong =
        c.space == NormalSpace::kWorld ? NormalSpace::kCamera : NormalSpace::kWorld;
    const detail::NormalSpaceChoice told =
        detail::choose_normal_space(wrong, s, true, "the layout says");
    EXPECT_EQ(told.space, wrong);
    EXPECT_NE(told.warning.find(std::string("--normal-space ") + normal_space_name(c.space)),
              std::string::npos)
        << told.warning;
  }
}

TEST(NormalSpaceTest, CameraAlongTheWorldAxesTakesEitherWithoutAWord) {
  // The camera's axes are the world's: world and camera space are the same reading.
  const Camera camera = looking({0.4, 1.6, 0.5}, {0, 0, 1});
  const Frame f = render(camera, kCorner);
  const detail::NormalSpaceScores s =
      detail::score_normal_spaces(f.world_normal, f.depth, camera, kWindow, kWindow);
  EXPECT_TRUE(s.alike[0][1]);
  EXPECT_FALSE(s.alike[0][2]);
  const detail::NormalSpaceChoice c =
      detail::choose_normal_space(NormalSpace::kAuto, s, true, "test");
  EXPECT_TRUE(c.space == NormalSpace::kWorld || c.space == NormalSpace::kCamera);
  EXPECT_EQ(c.warning, "");
}

TEST(NormalSpaceTest, NoWorldTransformScoresNoWorldSpace) {
  Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  const Frame f = render(camera, kCorner);
  camera.has_world_transform = false;  // as --fov gives it: the depth still unprojects the same
  const detail::NormalSpaceScores s =
      detail::score_normal_spaces(f.world_normal, f.depth, camera, kWindow, kWindow);
  EXPECT_TRUE(std::isnan(score_of(s, NormalSpace::kWorld)));
  // World normals read in a camera space agree with nothing: a doubtful reading, said so.
  const detail::NormalSpaceChoice c =
      detail::choose_normal_space(NormalSpace::kAuto, s, false, "test");
  EXPECT_NE(c.warning.find("no space clearly"), std::string::npos) << c.warning;
}

TEST(NormalSpaceTest, TooFewSurfacePixelsDecideNothing) {
  const Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  Frame f = render(camera, kCorner);
  for (float& v : f.depth.data()) v = std::numeric_limits<float>::infinity();
  for (int y = 30; y < 34; ++y)
    for (int x = 40; x < 44; ++x) f.depth.at(0, x, y) = render(camera, kCorner).depth.at(0, x, y);
  const detail::NormalSpaceScores s =
      detail::score_normal_spaces(f.camera_normal, f.depth, camera, kWindow, kWindow);
  EXPECT_LT(s.samples, 50u);
  const detail::NormalSpaceChoice c =
      detail::choose_normal_space(NormalSpace::kAuto, s, true, "test");
  EXPECT_EQ(c.space, NormalSpace::kWorld);
  EXPECT_NE(c.reason.find("too few"), std::string::npos) << c.reason;
}

TEST(NormalsFromDepthTest, MatchThePlanesNormals) {
  const Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  const Frame f = render(camera, kCorner);
  const Image n = detail::normals_from_depth(f.depth, camera, kWindow, kWindow);
  // Away from the planes' edges the depth's normal is the plane's.
  const int x = 20, y = 55;  // on the floor
  const Imath::V3d got{n.at(0, x, y), n.at(1, x, y), n.at(2, x, y)};
  const Imath::V3d want{f.camera_normal.at(0, x, y), f.camera_normal.at(1, x, y),
                        f.camera_normal.at(2, x, y)};
  EXPECT_GT(got.dot(want), 0.9999);
}

TEST(DepthAgainstPositionsTest, AgreeingKindIsSilentAtAnyScale) {
  const Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  const Frame f = render(camera, kCorner);
  EXPECT_EQ(detail::depth_position_mismatch(f.depth, f.position, camera, DepthKind::kPlanarZ, 1e9,
                                            "Z", "P"),
            "");
  EXPECT_EQ(detail::depth_position_mismatch(f.radial, f.position, camera, DepthKind::kRadial, 1e9,
                                            "Z", "P"),
            "");
  Image centimetres = f.depth;
  for (float& v : centimetres.data()) v *= 100;
  EXPECT_EQ(detail::depth_position_mismatch(centimetres, f.position, camera, DepthKind::kPlanarZ,
                                            1e12, "Z", "P"),
            "");
}

TEST(DepthAgainstPositionsTest, WrongKindNamesTheRightOne) {
  const Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  const Frame f = render(camera, kCorner);
  const std::string radial_as_planar = detail::depth_position_mismatch(
      f.radial, f.position, camera, DepthKind::kPlanarZ, 1e9, "depth.Z", "P");
  EXPECT_NE(radial_as_planar.find("depth.Z holds radial depth"), std::string::npos)
      << radial_as_planar;
  EXPECT_NE(radial_as_planar.find("--depth-kind radial"), std::string::npos);
  const std::string planar_as_radial = detail::depth_position_mismatch(
      f.depth, f.position, camera, DepthKind::kRadial, 1e9, "depth.Z", "P");
  EXPECT_NE(planar_as_radial.find("--depth-kind planar"), std::string::npos) << planar_as_radial;
  Image inverse = f.depth;
  for (float& v : inverse.data()) v = std::isfinite(v) ? 1 / v : 0;
  const std::string inverse_as_planar = detail::depth_position_mismatch(
      inverse, f.position, camera, DepthKind::kPlanarZ, 1e9, "depth.Z", "P");
  EXPECT_NE(inverse_as_planar.find("--depth-kind inverse"), std::string::npos) << inverse_as_planar;
}

TEST(DepthAgainstPositionsTest, BackgroundReadAsASurfaceIsNamed) {
  const Camera camera = looking({0.4, 1.6, 0.5}, {-0.35, -0.3, 1});
  // The floor alone: the upper part of the frame is sky.
  Frame f = render(camera, {{{0, 1, 0}, 0}});
  std::size_t sky = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      if (!std::isfinite(f.depth.at(0, x, y))) {
        f.depth.at(0, x, y) = 65504;  // half's largest value, as some renderers clear to
        ++sky;
      }
  ASSERT_GT(sky, static_cast<std::size_t>(kW * kH / 10));
  const std::string problem = detail::depth_position_mismatch(f.depth, f.position, camera,
                                                              DepthKind::kPlanarZ, 1e9, "Z", "P");
  EXPECT_NE(problem.find("Z is 65504 where the position pass P shows no surface"),
            std::string::npos)
      << problem;
  EXPECT_EQ(problem.find("--depth-kind"), std::string::npos) << problem;
  // The same sky at the layout's background value is background.
  EXPECT_EQ(detail::depth_position_mismatch(f.depth, f.position, camera, DepthKind::kPlanarZ, 6e4,
                                            "Z", "P"),
            "");
}

}  // namespace
}  // namespace ssgi
