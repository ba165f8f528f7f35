// The command line on passes judged by each other: a normal pass in another space than the
// layout says (warned about, and read right with --normal-space auto), and a depth pass whose
// kind the positions contradict.
#include <Imath/ImathMatrix.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

bool has(const std::string& text, const std::string& phrase) {
  return text.find(phrase) != std::string::npos;
}

// The sample's frame 1 (its camera in the header) with its world-space normals turned into the
// space of a camera looking down -z, as Maya's, Houdini's and Blender's do: the header's
// worldToCamera maps into camera space looking down +z, and z is negated.
void write_camera_gl_normals(const std::string& out) {
  ExrImage frame = read_exr(testdata("asrendered/header.0001.exr"));
  const OIIO::ParamValue* m = frame.spec.find_attribute("worldToCamera");
  ASSERT_NE(m, nullptr);
  const float* w2c = static_cast<const float*>(m->data());
  std::vector<float>& x = frame.planes.at("ViewLayer.Normal.X");
  std::vector<float>& y = frame.planes.at("ViewLayer.Normal.Y");
  std::vector<float>& z = frame.planes.at("ViewLayer.Normal.Z");
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double n[3] = {x[i], y[i], z[i]};
    double c[3] = {0, 0, 0};
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[j] += n[k] * w2c[k * 4 + j];
    x[i] = static_cast<float>(c[0]);
    y[i] = static_cast<float>(c[1]);
    z[i] = static_cast<float>(-c[2]);
  }
  write_exr(out, frame);
}

TEST_F(Cli, CameraSpaceNormalsAreFoundByAgreementWithTheDepth) {
  write_camera_gl_normals(path("camgl.0001.exr"));
  const CliResult world =
      run_ssgi({"run", testdata("asrendered/header.0001.exr"), "-o", path("world.exr"), "-q"});
  ASSERT_EQ(world.exit_code, 0) << world.err;

  // Read as the Blender layout says (world space), they contradict the depth: said, with the
  // space that agrees.
  const CliResult told = run_ssgi({"run", path("camgl.0001.exr"), "-o", path("told.exr")});
  ASSERT_EQ(told.exit_code, 0) << told.err;
  EXPECT_TRUE(has(told.err, "warning: " + path("camgl.0001.exr") +
                                ": the normals are read in world space as the blender layout "
                                "says, but agree with the depth's in camera-gl space"))
      << told.err;
  EXPECT_TRUE(has(told.err, "give --normal-space camera-gl")) << told.err;

  // Decided by agreement, they light the frame as the world-space pass does, without a word: the
  // same normals but for float rounding, which flips a few of the march's hit-or-miss decisions
  // where a ray grazes a depth step.
  const CliResult decided = run_ssgi(
      {"run", path("camgl.0001.exr"), "--normal-space", "auto", "-o", path("auto.exr"), "-q"});
  ASSERT_EQ(decided.exit_code, 0) << decided.err;
  EXPECT_EQ(decided.err, "");
  const ExrImage reference = read_exr(path("world.exr"));
  EXPECT_LT(IndirectRelRmse(read_exr(path("auto.exr")), reference, "ViewLayer.Depth.Z"), 1e-2);
  // Read in the wrong space the light is far off: the test can tell.
  EXPECT_GT(IndirectRelRmse(read_exr(path("told.exr")), reference, "ViewLayer.Depth.Z"), 0.05);

  const CliResult info = run_ssgi({"info", path("camgl.0001.exr"), "--normal-space", "auto"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_TRUE(has(info.out, "normals' space decided per frame by the depth")) << info.out;
  EXPECT_TRUE(has(info.out,
                  "normals:       frame 1: ViewLayer.Normal in camera-gl space, the "
                  "one that agrees with the depth (within 18 degrees"))
      << info.out;
  const CliResult json =
      run_ssgi({"info", path("camgl.0001.exr"), "--normal-space", "auto", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["layout"]["normal_space"], "auto");
  EXPECT_EQ(j["normals"]["frame"], 1);
  EXPECT_TRUE(has(j["normals"]["source"].get<std::string>(), "in camera-gl space"));
}

TEST_F(Cli, NormalSpaceGivenIsUsedAndABadOneIsAUsageError) {
  write_camera_gl_normals(path("camgl.0001.exr"));
  const CliResult given = run_ssgi(
      {"run", path("camgl.0001.exr"), "--normal-space", "camera-gl", "-o", path("gl.exr")});
  ASSERT_EQ(given.exit_code, 0) << given.err;
  EXPECT_FALSE(has(given.err, "warning")) << given.err;
  const CliResult decided = run_ssgi(
      {"run", path("camgl.0001.exr"), "--normal-space", "auto", "-o", path("auto.exr"), "-q"});
  ASSERT_EQ(decided.exit_code, 0) << decided.err;
  // The same light; the headers differ in the command line they record.
  EXPECT_TRUE(read_exr(path("gl.exr")).planes == read_exr(path("auto.exr")).planes);
  expect_usage_error(
      run_ssgi({"run", path("camgl.0001.exr"), "--normal-space", "object", "-o", path("x.exr")}),
      "run", "unknown --normal-space 'object' (auto, world, camera, camera-gl)");
}

TEST_F(Cli, DepthOfAnotherKindThanTheLayoutsIsNamed) {
  // The Blender layout's depth is planar; read as distance along the ray, the positions say
  // otherwise.
  const std::string file = testdata("asrendered/header.0001.exr");
  const CliResult r = run_ssgi({"info", file, "--depth-kind", "radial"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "warning: " + file +
                             ": ViewLayer.Depth.Z holds planar depth by the position pass "
                             "ViewLayer.Position"))
      << r.err;
  EXPECT_TRUE(has(r.err, "give --depth-kind planar")) << r.err;
  // Read as it is, not a word.
  const CliResult right = run_ssgi({"info", file});
  ASSERT_EQ(right.exit_code, 0) << right.err;
  EXPECT_EQ(right.err, "");
}

}  // namespace
}  // namespace cli_test
