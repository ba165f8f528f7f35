// The command line on frames whose camera comes from their position pass: Blender's multilayer
// EXR as Blender writes it (no camera in the header), a fisheye's positions (refused), a header
// camera that disagrees with the positions (warned about), and the Cycles sample data with its
// header cameras stripped.
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

}  // namespace
}  // namespace cli_test
