// Views end to end (--view, --latlong-view): the static room with its six cube faces and its
// lat-long as stills, the pan with a view sequence per face, what `info` says of them, the same
// bits for any run, and the views a run must refuse or repair.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

const char* const kFaces[] = {"px", "nx", "py", "ny", "pz", "nz"};

// --view for each face of `name` (a still, or a sequence when `sequence`).
std::vector<std::string> face_views(const std::string& name, bool sequence) {
  std::vector<std::string> args;
  for (const char* f : kFaces) {
    args.push_back("--view");
    args.push_back(testdata("views/" + name + "." + f + (sequence ? ".####.exr" : ".exr")));
  }
  return args;
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

double mean(const std::vector<float>& v) {
  double sum = 0;
  for (float x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

bool all_finite(const ExrImage& image) {
  for (const auto& [name, plane] : image.planes)
    for (float v : plane)
      if (!std::isfinite(v) && name.rfind("ViewLayer.", 0) != 0) return false;
  return true;
}

TEST_F(Cli, ViewsBringTheLightTheFrameDoesNotShowAndCountAsTraced) {
  const std::string in = testdata("static/static.####.exr");
  const std::vector<std::string> base = {"run", in, "--frames", "1-3", "-q"};
  ASSERT_EQ(run_ssgi(with(base, {"-o", path("none.####.exr")})).exit_code, 0);
  const CliResult faces =
      run_ssgi(with(with(base, {"-o", path("faces.####.exr")}), face_views("static", false)));
  ASSERT_EQ(faces.exit_code, 0) << faces.err;
  const CliResult latlong = run_ssgi(with(base, {"-o", path("latlong.####.exr"), "--latlong-view",
                                                 testdata("views/static.latlong.exr")}));
  ASSERT_EQ(latlong.exit_code, 0) << latlong.err;
  const ExrImage none = read_exr(path("none.0002.exr")),
                 with_faces = read_exr(path("faces.0002.exr")),
                 with_latlong = read_exr(path("latlong.0002.exr"));
  const double c0 = mean(none.planes.at("coverage.Y")),
               c1 = mean(with_faces.planes.at("coverage.Y")),
               c2 = mean(with_latlong.planes.at("coverage.Y"));
  std::printf("coverage: %.3f without views, %.3f with six faces, %.3f with the lat-long\n", c0, c1,
              c2);
  // The room's walls behind and beside the camera are found in the views: far more of the light
  // is traced, not the miss model's.
  EXPECT_GT(c1, c0 + 0.2);
  EXPECT_GT(c2, c0 + 0.1);
  // And the light changes with it.
  EXPECT_GT(
      std::fabs(mean(with_faces.planes.at("indirect.R")) - mean(none.planes.at("indirect.R"))),
      0.01);
  // The input's channels pass through as they were.
  for (const auto& [name, plane] : none.planes)
    if (name.rfind("ViewLayer.", 0) == 0) {
      EXPECT_EQ(std::memcmp(plane.data(), with_faces.planes.at(name).data(),
                            plane.size() * sizeof(float)),
                0)
          << name;
    }
  EXPECT_TRUE(all_finite(with_faces));
  EXPECT_TRUE(all_finite(with_latlong));
}

TEST_F(Cli, ViewsGiveTheSameBitsInAnyRun) {
  // The pan moves: a view sequence per face, read per frame. Default settings (window +-2),
  // multiframe on too, so that the views' misses go on to the other frames.
  const std::string in = testdata("pan/pan.####.exr");
  const std::vector<std::string> views =
      with(face_views("pan", true),
           {"--latlong-view", testdata("views/pan.latlong.####.exr"), "--multiframe", "on", "-q"});
  const auto run = [&](const std::string& name, std::vector<std::string> extra) {
    const CliResult r =
        run_ssgi(with(with({"run", in, "-o", path(name + ".####.exr")}, views), extra));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  };
  run("t1", {"--threads", "1"});
  run("t2", {"--threads", "2", "--frames-in-flight", "3"});
  run("chunk", {"--frames", "3-4", "--threads", "2"});
  for (int f = 1; f <= 6; ++f) {
    const std::string frame = ".000" + std::to_string(f) + ".exr";
    const ExrImage a = read_exr(path("t1" + frame)), b = read_exr(path("t2" + frame));
    const bool chunked = f == 3 || f == 4;
    const ExrImage c = chunked ? read_exr(path("chunk" + frame)) : ExrImage();
    for (const std::string& ch : kOurChannels) {
      const std::vector<float>& x = a.planes.at(ch);
      EXPECT_EQ(std::memcmp(x.data(), b.planes.at(ch).data(), x.size() * sizeof(float)), 0)
          << "1 vs 2 threads, frame " << f << " " << ch;
      if (chunked) {
        EXPECT_EQ(std::memcmp(x.data(), c.planes.at(ch).data(), x.size() * sizeof(float)), 0)
            << "whole vs chunked, frame " << f << " " << ch;
      }
    }
  }
}

TEST_F(Cli, InfoListsEachViewWithItsCamera) {
  const CliResult text = run_ssgi(with({"info", testdata("pan/pan.####.exr"), "--latlong-view",
                                        testdata("views/pan.latlong.####.exr")},
                                       face_views("pan", true)));
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("views/pan.px.0001.exr: 16x16 pinhole"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("views/pan.latlong.0001.exr: 48x24 lat-long (six cube faces of 12)"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("horizontal fov 90.0000 deg"), std::string::npos);
  EXPECT_NE(text.out.find("at the shot camera's position"), std::string::npos);

  // A view from elsewhere is allowed, and said: frame 1's back face for the static room, whose
  // camera stands 0.6 m from the pan's first.
  const CliResult elsewhere = run_ssgi(
      {"info", testdata("pan/pan.####.exr"), "--json", "--view", testdata("views/static.nz.exr")});
  ASSERT_EQ(elsewhere.exit_code, 0) << elsewhere.err;
  const nlohmann::json j = nlohmann::json::parse(elsewhere.out);
  ASSERT_EQ(j["views"].size(), 1u);
  const nlohmann::json& v = j["views"][0];
  EXPECT_EQ(v["projection"], "pinhole");
  EXPECT_EQ(v["still"], true);
  EXPECT_EQ(v["at_shot_camera"], false);
  EXPECT_GT(v["distance_from_shot_camera"].get<double>(), 0.1);
  EXPECT_NEAR(v["camera"]["hfov_deg"].get<double>(), 90.0, 1e-4);  // float matrices
}

TEST_F(Cli, ViewsThatCannotBeReadAreRefusedBeforeAnythingIsWritten) {
  const std::string in = testdata("pan/pan.####.exr");
  // A view file that is not there: exit 4, naming it.
  const CliResult missing =
      run_ssgi({"run", in, "-o", path("o.####.exr"), "--view", testdata("views/absent.####.exr")});
  EXPECT_EQ(missing.exit_code, 4) << missing.err;
  expect_one_error(missing, testdata("views/absent.0001.exr"), "missing");
  // A view without a camera: exit 3, naming it.
  const CliResult no_camera =
      run_ssgi({"run", in, "-o", path("o.####.exr"), "--view", testdata("views/nocamera.exr")});
  EXPECT_EQ(no_camera.exit_code, 3) << no_camera.err;
  expect_one_error(no_camera, testdata("views/nocamera.exr"), "no camera");
  // A view sequence that does not cover the frames the run reads: frame 2 reads frames 1 to 4,
  // and the view has only 1 to 3.
  for (int f = 1; f <= 3; ++f)
    fs::copy_file(testdata("views/pan.pz.000" + std::to_string(f) + ".exr"),
                  path("short.000" + std::to_string(f) + ".exr"));
  const CliResult short_view = run_ssgi(
      {"run", in, "-o", path("o.####.exr"), "--frames", "2", "--view", path("short.####.exr")});
  EXPECT_EQ(short_view.exit_code, 4) << short_view.err;
  expect_one_error(short_view, path("short.0004.exr"), "a view covers every frame the run reads");
  // A view without albedo: exit 3 naming it, before anything is written.
  ExrImage no_albedo = read_exr(testdata("views/static.nz.exr"));
  std::vector<std::string> kept;
  for (const std::string& c : no_albedo.spec.channelnames)
    if (c.find(".DiffCol.") == std::string::npos) kept.push_back(c);
  no_albedo.spec.channelnames = kept;
  write_exr(path("noalbedo.exr"), no_albedo);
  const CliResult albedo =
      run_ssgi({"run", in, "-o", path("o.####.exr"), "--view", path("noalbedo.exr")});
  EXPECT_EQ(albedo.exit_code, 3) << albedo.err;
  expect_one_error(albedo, path("noalbedo.exr"), "has no albedo channels");
  for (const std::string& name : entries())
    EXPECT_EQ(name.rfind("o.", 0), std::string::npos) << name;
}

TEST_F(Cli, SkipExistingKeepsOnlyFramesMadeWithTheSameViews) {
  const std::string in = testdata("static/static.####.exr");
  const std::vector<std::string> base = {
      "run", in, "--frames", "1", "-o", path("o.####.exr"), "-q", "--skip-existing"};
  ASSERT_EQ(run_ssgi(base).exit_code, 0);
  const ExrImage without = read_exr(path("o.0001.exr"));
  // The views change the light: a frame made without them is made again.
  ASSERT_EQ(run_ssgi(with(base, face_views("static", false))).exit_code, 0);
  const ExrImage with_views = read_exr(path("o.0001.exr"));
  EXPECT_GT(mean(with_views.planes.at("coverage.Y")), mean(without.planes.at("coverage.Y")) + 0.2);
  // And one made with them is kept when they are the same: the file is not written again.
  const auto written = fs::last_write_time(path("o.0001.exr"));
  const CliResult again = run_ssgi(with(base, face_views("static", false)));
  ASSERT_EQ(again.exit_code, 0);
  EXPECT_EQ(fs::last_write_time(path("o.0001.exr")), written);
}

TEST_F(Cli, NonFiniteValuesInAViewAreHolesNeverNaN) {
  const CliResult r = run_ssgi({"run", testdata("static/static.####.exr"), "--frames", "1", "-o",
                                path("o.####.exr"), "--view", testdata("views/nan.exr"), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ExrImage out = read_exr(path("o.0001.exr"));
  EXPECT_TRUE(all_finite(out));
  EXPECT_GT(mean(out.planes.at("indirect.R")), 0.0);
}

}  // namespace
}  // namespace cli_test
