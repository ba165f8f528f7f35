// The command line on frames Blender wrote itself, with nothing added (testdata/blender/, made
// by tests/blender/render_gbuffer.py): no camera in their headers, so it is fitted to their
// Position pass, and camera.json beside them is the camera Blender rendered with.
#include <Imath/ImathMatrix.h>
#include <Imath/ImathVec.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

const std::string kFrames = testdata("blender/corner.####.exr");
const std::string kSidecar = testdata("blender/camera.json");
constexpr int kFirst = 1, kLast = 3;
constexpr int kWidth = 64, kHeight = 36;

std::string frame_file(const std::string& stem, int frame) {
  char number[8];
  std::snprintf(number, sizeof number, "%04d", frame);
  return stem + "." + number + ".exr";
}

// A frame's worldToCamera or worldToNDC from camera.json (16 numbers, Imath's row-vector
// layout, as the sidecar format reads them).
Imath::M44d sidecar_matrix(int frame, const std::string& key) {
  std::ifstream in(kSidecar);
  const nlohmann::json doc = nlohmann::json::parse(in);
  for (const nlohmann::json& f : doc["frames"]) {
    if (f["frame"].get<int>() != frame) continue;
    const std::vector<double> v = f[key].get<std::vector<double>>();
    EXPECT_EQ(v.size(), 16u);
    Imath::M44d m;
    for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = v[i];
    return m;
  }
  ADD_FAILURE() << "no frame " << frame << " in " << kSidecar;
  return {};
}

// The true camera of a frame as camera space (x right, y up, +z forward) to NDC x:
// ndc_x = scale * x / z + centre. Its pixel-space focal length is scale * W, its principal
// point centre * W.
struct NdcX {
  double scale, centre;
};

NdcX true_ndc_x(int frame) {
  const Imath::M44d camera_to_ndc =
      sidecar_matrix(frame, "worldToCamera").inverse() * sidecar_matrix(frame, "worldToNDC");
  auto ndc_x = [&](const Imath::V3d& p) {
    Imath::V3d q;
    camera_to_ndc.multVecMatrix(p, q);  // divides by w (= camera-space z)
    return q.x;
  };
  const double centre = ndc_x({0, 0, 1});
  return {ndc_x({1, 0, 1}) - centre, centre};
}

// The angle the display window spans horizontally, its left and right edges taken apart (the
// principal point is off-centre): what ssgi info prints as the horizontal fov.
double true_hfov_deg(int frame) {
  const NdcX c = true_ndc_x(frame);
  return (std::atan(c.centre / c.scale) + std::atan((1 - c.centre) / c.scale)) * 180 / M_PI;
}

TEST_F(Cli, BlenderFramesHoldNoCameraInTheirHeaders) {
  for (int f = kFirst; f <= kLast; ++f) {
    const ExrImage frame = read_exr(frame_file(testdata("blender/corner"), f));
    SCOPED_TRACE(f);
    // Blender's own multilayer EXR, as Blender writes it.
    EXPECT_NE(frame.spec.find_attribute("BlenderMultiChannel"), nullptr);
    for (const char* name : {"worldToCamera", "worldToNDC", "worldToScreen", "worldtocamera",
                             "worldtoscreen", "exr/worldToCamera", "exr/worldToNDC"})
      EXPECT_EQ(frame.spec.find_attribute(name), nullptr) << name;
    EXPECT_TRUE(frame.channel_names().count("ViewLayer.Position.X"));
  }
}

TEST_F(Cli, BlenderSidecarIsTheCameraBlenderRenderedWith) {
  // camera.json's worldToNDC projects every surface pixel's Position back onto that pixel's
  // centre. The pass is the mean of the 8 samples' hit points, and the 0.01-pixel filter puts
  // each sample within 0.005 px of the centre (their mean lies 5.3e-4 px off, the same at
  // every pixel); a camera without the lens shift would be 3.2 px off.
  for (int f = kFirst; f <= kLast; ++f) {
    SCOPED_TRACE(f);
    const ExrImage frame = read_exr(frame_file(testdata("blender/corner"), f));
    const Imath::M44d ndc = sidecar_matrix(f, "worldToNDC");
    const std::vector<float>& depth = frame.planes.at("ViewLayer.Depth.Z");
    double farthest_px = 0;
    int surfaces = 0;
    for (int j = 0; j < kHeight; ++j) {
      for (int i = 0; i < kWidth; ++i) {
        const std::size_t p = static_cast<std::size_t>(j) * kWidth + i;
        if (!(depth[p] < 1e9f)) continue;
        const Imath::V3d world(frame.planes.at("ViewLayer.Position.X")[p],
                               frame.planes.at("ViewLayer.Position.Y")[p],
                               frame.planes.at("ViewLayer.Position.Z")[p]);
        Imath::V3d q;
        ndc.multVecMatrix(world, q);
        farthest_px = std::max(
            {farthest_px, std::abs(q.x * kWidth - (i + 0.5)), std::abs(q.y * kHeight - (j + 0.5))});
        ++surfaces;
      }
    }
    ASSERT_GT(surfaces, kWidth * kHeight / 2);
    EXPECT_LT(farthest_px, 0.005);
    // The lens shift (render_gbuffer.py: shift_x 0.05 of the width) is in it: the principal
    // point is 3.2 px left of the image centre.
    EXPECT_NEAR(true_ndc_x(f).centre * kWidth, kWidth / 2 - 0.05 * kWidth, 1e-3);
  }
}

TEST_F(Cli, BlenderInfoNamesThePositionPassAndTheTrueFov) {
  const CliResult text = run_ssgi({"info", kFrames});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(text.err, "");
  const CliResult json = run_ssgi({"info", kFrames, "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json cameras = nlohmann::json::parse(json.out)["cameras"];
  ASSERT_EQ(cameras.size(), static_cast<std::size_t>(kLast - kFirst + 1)) << json.out;
  for (int f = kFirst; f <= kLast; ++f) {
    SCOPED_TRACE(f);
    // 73.542 degrees. A camera that dropped the lens shift would span 2 atan(18 / 24) = 73.740,
    // within the 0.2 degrees asked of the fit; the 1e-3 (the fit meets 7e-5) tells them apart.
    const double truth = true_hfov_deg(f);
    const std::string head =
        "  frame " + std::to_string(f) + "      position pass ViewLayer.Position (fit, residual ";
    const std::size_t at = text.out.find(head);
    ASSERT_NE(at, std::string::npos) << text.out;
    const std::size_t fov_at = text.out.find("horizontal fov ", at);
    ASSERT_NE(fov_at, std::string::npos) << text.out;
    EXPECT_NEAR(std::stod(text.out.substr(fov_at + 15)), truth, 0.2);
    EXPECT_NEAR(std::stod(text.out.substr(fov_at + 15)), truth, 1e-3);

    const nlohmann::json& c = cameras[f - kFirst];
    EXPECT_EQ(c["source"].get<std::string>().rfind("position pass ViewLayer.Position (fit", 0), 0u)
        << c.dump();
    EXPECT_NEAR(c["hfov_deg"].get<double>(), truth, 0.2);
    EXPECT_NEAR(c["hfov_deg"].get<double>(), truth, 1e-3);
    // Cycles' Position pass at the pixel centres fits to float precision.
    ASSERT_TRUE(c["fit_residual_px"].is_number()) << c.dump();
    EXPECT_LT(c["fit_residual_px"].get<double>(), 1e-3);
  }
}

TEST_F(Cli, BlenderFramesRunWithNoFlagsAsWithTheirTrueCamera) {
  const CliResult fitted = run_ssgi({"run", kFrames, "-o", path("fit.####.exr")});
  ASSERT_EQ(fitted.exit_code, 0) << fitted.err;
  EXPECT_EQ(fitted.err.find("warning"), std::string::npos) << fitted.err;
  const CliResult sidecar =
      run_ssgi({"run", kFrames, "--camera", kSidecar, "-o", path("true.####.exr"), "-q"});
  ASSERT_EQ(sidecar.exit_code, 0) << sidecar.err;
  for (int f = kFirst; f <= kLast; ++f) {
    SCOPED_TRACE(f);
    const ExrImage fit = read_exr(frame_file(path("fit"), f));
    const ExrImage truth = read_exr(frame_file(path("true"), f));
    // The light is there: a mean indirect of zero would make any relRMSE meaningless.
    const std::vector<float>& depth = truth.planes.at("ViewLayer.Depth.Z");
    double sum = 0;
    std::size_t surfaces = 0;
    for (std::size_t p = 0; p < depth.size(); ++p) {
      if (!(depth[p] < 1e9f)) continue;
      sum += fit.planes.at("indirect.R")[p] + fit.planes.at("indirect.G")[p] +
             fit.planes.at("indirect.B")[p];
      ++surfaces;
    }
    ASSERT_GT(surfaces, depth.size() / 2);
    EXPECT_GT(sum / (3 * surfaces), 0.1);  // 0.41 here
    // 0.35% to 0.53% here. The limit asked of it, 2%, is met by the fitted camera and not by one
    // that drops the lens shift (the true camera centred gives 4.6% to 5.5%).
    EXPECT_LT(IndirectRelRmse(fit, truth, "ViewLayer.Depth.Z"), 0.02);
  }
}

}  // namespace
}  // namespace cli_test
