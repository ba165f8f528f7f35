// The command line on frames whose camera comes from their position pass: Blender's multilayer
// EXR as Blender writes it (no camera in the header), a fisheye's positions (refused), a header
// camera that disagrees with the positions (warned about), the Cycles sample data with its header
// cameras stripped, and the cameras other renderers write into their headers.
#include <Imath/ImathMatrix.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

const std::string kSharedData = SSGI_SHARED_DATA_DIR;

TEST_F(Cli, BlenderFrameWithoutCameraGetsItFromItsPositionPass) {
  // The sample's frame 1 as Blender writes it (world normals, a Position pass, no camera in the
  // header) against the same frame with its camera in the header: the fitted camera is the
  // true one to float precision, so the light differs by far less than 2% (the limit asked of
  // it): 0.23%, from the march's hit-or-miss decisions where a ray grazes a depth step, which a
  // last-digit change of the camera flips.
  const CliResult fitted =
      run_ssgi({"run", testdata("asrendered/blender.0001.exr"), "-o", path("fit.exr"), "-q"});
  ASSERT_EQ(fitted.exit_code, 0) << fitted.err;
  EXPECT_EQ(fitted.err, "");
  const CliResult header =
      run_ssgi({"run", testdata("asrendered/header.0001.exr"), "-o", path("header.exr"), "-q"});
  ASSERT_EQ(header.exit_code, 0) << header.err;
  const double rel =
      IndirectRelRmse(read_exr(path("fit.exr")), read_exr(path("header.exr")), "ViewLayer.Depth.Z");
  EXPECT_LT(rel, 0.02);
  EXPECT_LT(rel, 5e-3);
}

TEST_F(Cli, InfoNamesThePositionPassAndTheFittedFov) {
  const std::string file = testdata("asrendered/blender.0001.exr");
  const CliResult text = run_ssgi({"info", file});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(text.err, "");
  const std::string head = "  frame 1      position pass ViewLayer.Position (fit, residual ";
  const std::size_t at = text.out.find(head);
  ASSERT_NE(at, std::string::npos) << text.out;
  const std::size_t fov_at = text.out.find("horizontal fov ", at);
  ASSERT_NE(fov_at, std::string::npos) << text.out;
  // The sample camera's horizontal field of view is 65 degrees.
  EXPECT_NEAR(std::stod(text.out.substr(fov_at + 15)), 65.0, 0.2);

  const CliResult json = run_ssgi({"info", file, "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json camera = nlohmann::json::parse(json.out)["cameras"][0];
  EXPECT_NEAR(camera["hfov_deg"].get<double>(), 65.0, 0.2);
  ASSERT_TRUE(camera["fit_residual_px"].is_number()) << camera.dump();
  // Exact positions stored as float: far below a thousandth of a pixel.
  EXPECT_LT(camera["fit_residual_px"].get<double>(), 1e-3);
  // A header camera has no fit.
  const CliResult header = run_ssgi({"info", testdata("asrendered/header.0001.exr"), "--json"});
  EXPECT_FALSE(nlohmann::json::parse(header.out)["cameras"][0].contains("fit_residual_px"));
}

TEST_F(Cli, FisheyePositionsAreRefused) {
  const std::string file = testdata("asrendered/fisheye.0001.exr");
  const CliResult r = run_ssgi({"run", file, "-o", path("out.exr")});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, file,
                   "no camera in the header, and its position pass ViewLayer.Position does not "
                   "fit a pinhole camera (residual ");
  EXPECT_NE(r.err.find("give --camera or --fov"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out.exr")));
  // --fov still gives it a camera.
  EXPECT_EQ(run_ssgi({"run", file, "-o", path("out.exr"), "--fov", "65", "-q"}).exit_code, 0);
}

TEST_F(Cli, HeaderCameraThatDisagreesWithThePositionsIsWarnedAboutOnce) {
  // Frame 1's passes under frame 2's camera, turned by 2 degrees: 3 px apart. The header wins.
  const std::string file = testdata("asrendered/otherheader.0001.exr");
  const CliResult r = run_ssgi({"run", file, "-o", path("out.exr")});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::size_t warnings = 0;
  for (const std::string& line : r.err_lines()) {
    if (line.rfind("ssgi: warning: ", 0) != 0) continue;
    ++warnings;
    EXPECT_EQ(line, "ssgi: warning: " + file +
                        ": the header camera (header worldToCamera/worldToNDC) and the position "
                        "pass ViewLayer.Position disagree by 3.02 px RMS; the header camera is "
                        "used");
  }
  EXPECT_EQ(warnings, 1u) << r.err;
  // Where they agree, nothing is said.
  const CliResult agree = run_ssgi({"info", testdata("asrendered/header.0001.exr")});
  EXPECT_EQ(agree.err, "");
}

TEST_F(Cli, PositionsInTheHeaderCamerasSpaceAreNotADisagreement) {
  // The frame's positions moved into its camera space (x right, y up, +z forward), as
  // RenderMan writes P: they agree with the header's projection alone.
  ExrImage frame = read_exr(testdata("asrendered/header.0001.exr"));
  const OIIO::ParamValue* m = frame.spec.find_attribute("worldToCamera");
  ASSERT_NE(m, nullptr);
  const float* w2c = static_cast<const float*>(m->data());
  std::vector<float>& x = frame.planes.at("ViewLayer.Position.X");
  std::vector<float>& y = frame.planes.at("ViewLayer.Position.Y");
  std::vector<float>& z = frame.planes.at("ViewLayer.Position.Z");
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double p[4] = {x[i], y[i], z[i], 1};
    double c[3] = {0, 0, 0};
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 4; ++k) c[j] += p[k] * w2c[k * 4 + j];
    x[i] = static_cast<float>(c[0]);
    y[i] = static_cast<float>(c[1]);
    z[i] = static_cast<float>(c[2]);
  }
  write_exr(path("camspace.0001.exr"), frame);
  const CliResult r = run_ssgi({"info", path("camspace.0001.exr")});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

TEST_F(Cli, CyclesFramesWithTheirHeaderCamerasStripped) {
  const std::string source = kSharedData + "/room/room.0003.exr";
  if (!fs::exists(source)) GTEST_SKIP() << "no sample data at " << kSharedData;
  // The same frame with and without the header camera, each a shot of its own (no neighbours).
  ExrImage frame = read_exr(source);
  write_exr(path("header.0003.exr"), frame);
  frame.spec.erase_attribute("worldToCamera");
  frame.spec.erase_attribute("worldToNDC");
  write_exr(path("stripped.0003.exr"), frame);

  const CliResult header = run_ssgi({"info", path("header.0003.exr"), "--json"});
  const CliResult fitted = run_ssgi({"info", path("stripped.0003.exr"), "--json"});
  ASSERT_EQ(header.exit_code, 0) << header.err;
  ASSERT_EQ(fitted.exit_code, 0) << fitted.err;
  EXPECT_EQ(header.err, "");  // the header camera and the Position pass agree
  const nlohmann::json h = nlohmann::json::parse(header.out)["cameras"][0];
  const nlohmann::json f = nlohmann::json::parse(fitted.out)["cameras"][0];
  EXPECT_EQ(h["source"], "header worldToCamera/worldToNDC");
  EXPECT_EQ(f["source"].get<std::string>().rfind("position pass ViewLayer.Position (fit", 0), 0u);
  // Cycles' Position pass fits to ~1.5e-5 px; the fov agrees to ~1e-5 degrees.
  EXPECT_LT(f["fit_residual_px"].get<double>(), 1e-3);
  EXPECT_NEAR(f["hfov_deg"].get<double>(), h["hfov_deg"].get<double>(), 1e-3);

  ASSERT_EQ(run_ssgi({"run", path("header.0003.exr"), "-o", path("h.exr"), "-q"}).exit_code, 0);
  ASSERT_EQ(run_ssgi({"run", path("stripped.0003.exr"), "-o", path("s.exr"), "-q"}).exit_code, 0);
  EXPECT_LT(IndirectRelRmse(read_exr(path("s.exr")), read_exr(path("h.exr")), "ViewLayer.Depth.Z"),
            0.01);
}

// The header camera of frame 1 (the library's camera space: x right, y up, +z forward) and its
// horizontal fov, from the fixture that carries it.
struct TrueCamera {
  Imath::M44d world_to_camera;
  double hfov_deg = 0;
};

TrueCamera true_camera(const ExrImage& frame) {
  const OIIO::ParamValue* m = frame.spec.find_attribute("worldToCamera");
  const float* v = static_cast<const float*>(m->data());
  TrueCamera c;
  for (int i = 0; i < 16; ++i) c.world_to_camera[i / 4][i % 4] = v[i];
  c.hfov_deg = 65;  // testdata/README.md: the sample's camera
  return c;
}

void set_matrix(OIIO::ImageSpec& spec, const std::string& name, const Imath::M44d& m) {
  float v[16];
  for (int i = 0; i < 16; ++i) v[i] = static_cast<float>(m[i / 4][i % 4]);
  spec.attribute(name, OIIO::TypeDesc::TypeMatrix44, v);
}

// A camera looking down -z where ours looks down +z: the same transform with z negated.
const Imath::M44d kFlipZ(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1);

// Frame 1 with its camera as each renderer writes it into its header, in that renderer's own
// attribute names and conventions (camera_header.cpp), and no OpenEXR camera: the camera read
// back is the true one, so the position pass agrees with it (no warning) and the light is the
// true camera's.
TEST_F(Cli, RenderersOwnHeaderCamerasAreRead) {
  const ExrImage source = read_exr(testdata("asrendered/header.0001.exr"));
  const TrueCamera truth = true_camera(source);
  const Imath::M44d camera_to_world = truth.world_to_camera.inverse();
  const double kRad = 3.14159265358979323846 / 180;
  ASSERT_EQ(run_ssgi({"run", testdata("asrendered/header.0001.exr"), "-o", path("true.exr"), "-q"})
                .exit_code,
            0);
  const ExrImage reference = read_exr(path("true.exr"));

  struct Renderer {
    std::string name, source;
    std::function<void(ExrImage&)> write;
  };
  const std::vector<Renderer> renderers = {
      {"vray", "header V-Ray cameraTransform/cameraFov",
       [&](ExrImage& f) {
         // Camera-to-world of a camera looking down -Z, its translation in the last column.
         Imath::M44d t = (kFlipZ * camera_to_world).transposed();
         set_matrix(f.spec, "cameraTransform", t);
         f.spec.attribute("cameraFov", static_cast<float>(truth.hfov_deg));
         f.spec.attribute("cameraProjection", 0);
       }},
      {"arnold", "header Arnold worldToCamera/CameraFov",
       [&](ExrImage& f) {
         set_matrix(f.spec, "worldToCamera", truth.world_to_camera * kFlipZ);
         f.spec.attribute("CameraFov", static_cast<float>(truth.hfov_deg));
       }},
      {"redshift", "header Redshift rs/camera/transform/fov",
       [&](ExrImage& f) {
         set_matrix(f.spec, "rs/camera/transform", camera_to_world);
         f.spec.attribute("rs/camera/fov", static_cast<float>(truth.hfov_deg * kRad));
         f.spec.attribute("rs/camera/shift", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 2),
                          std::vector<float>{0, 0}.data());
       }},
      {"unreal", "header Unreal unreal/camera/curPos/curRot/FinalImage/fov",
       [&](ExrImage& f) {
         // Unreal's world is left-handed: the scene mirrored in y, positions and normals with
         // it, so that the camera is a rotation there, given as pitch, yaw and roll.
         const Imath::M44d mirror(1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1);
         for (const char* axis : {"ViewLayer.Position.Y", "ViewLayer.Normal.Y"})
           for (float& v : f.planes.at(axis)) v = -v;
         const Imath::M44d c2w = camera_to_world * mirror;  // rows: right, up, forward, eye
         const Imath::V3d right(c2w[0][0], c2w[0][1], c2w[0][2]);
         const Imath::V3d up(c2w[1][0], c2w[1][1], c2w[1][2]);
         const Imath::V3d forward(c2w[2][0], c2w[2][1], c2w[2][2]);
         const double pitch = std::asin(forward.z) / kRad;
         const double yaw = std::atan2(forward.y, forward.x) / kRad;
         const double roll = std::atan2(-right.z, up.z) / kRad;
         const auto text = [](double v) {
           char buf[40];
           std::snprintf(buf, sizeof buf, "%.9g", v);
           return std::string(buf);
         };
         f.spec.attribute("unreal/camera/curPos/x", text(c2w[3][0]));
         f.spec.attribute("unreal/camera/curPos/y", text(c2w[3][1]));
         f.spec.attribute("unreal/camera/curPos/z", text(c2w[3][2]));
         f.spec.attribute("unreal/camera/curRot/pitch", text(pitch));
         f.spec.attribute("unreal/camera/curRot/yaw", text(yaw));
         f.spec.attribute("unreal/camera/curRot/roll", text(roll));
         f.spec.attribute("unreal/camera/FinalImage/fov", text(truth.hfov_deg));
       }},
  };
  for (const Renderer& r : renderers) {
    SCOPED_TRACE(r.name);
    ExrImage frame = source;
    frame.spec.erase_attribute("worldToCamera");
    frame.spec.erase_attribute("worldToNDC");
    r.write(frame);
    const std::string file = path(r.name + ".0001.exr");
    write_exr(file, frame);
    const CliResult info = run_ssgi({"info", file, "--json"});
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_EQ(info.err, "");  // the header camera and the position pass agree
    const nlohmann::json c = nlohmann::json::parse(info.out)["cameras"][0];
    EXPECT_EQ(c["source"], r.source);
    EXPECT_NEAR(c["hfov_deg"].get<double>(), truth.hfov_deg, 1e-4);
    const CliResult run = run_ssgi({"run", file, "-o", path(r.name + ".exr"), "-q"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_LT(IndirectRelRmse(read_exr(path(r.name + ".exr")), reference, "ViewLayer.Depth.Z"),
              0.02);
  }
}

}  // namespace
}  // namespace cli_test
