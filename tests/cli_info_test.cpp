// `ssgi info`: the report on a sequence (text and JSON), layout detection, channel flags and
// --check's decoding of every frame.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

TEST_F(Cli, InfoReportsTheSampleSequence) {
  const CliResult r = run_ssgi({"info", testdata("sample/sample.####.exr")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  // The facts a user checks before a run: layout, size, frames, cameras and the plan.
  EXPECT_NE(r.out.find("\nlayout:        blender (Blender Cycles"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\nresolution:    96x64\n"), std::string::npos);
  EXPECT_NE(r.out.find("\ndisplay window (0,0)-(95,63)\n"), std::string::npos);
  EXPECT_NE(r.out.find("\nframes:        1-6 (6 to write, 6 on disk)\n"), std::string::npos);
  EXPECT_NE(r.out.find("  depth        ViewLayer.Depth.Z\n"), std::string::npos);
  // The sample's camera has a 65 degree horizontal field of view in every frame's header.
  for (int f = 1; f <= 6; ++f) {
    const std::string line = "  frame " + std::to_string(f) +
                             "      header worldToCamera/worldToNDC, horizontal fov 65.0000 deg\n";
    EXPECT_NE(r.out.find(line), std::string::npos) << line;
  }
  const std::size_t plan = r.out.find("\nplan:\n");
  ASSERT_NE(plan, std::string::npos);
  EXPECT_NE(r.out.find("  trace: slices (visibility bitmask), 2 slices", plan), std::string::npos);
  EXPECT_NE(r.out.find("  composite: ", plan), std::string::npos);
}

TEST_F(Cli, InfoJsonIsTheSameReportForMachines) {
  // The report as one JSON document on stdout: layout, channels, cameras and plan; run and
  // reference refuse --json.
  const std::string in = testdata("sample/sample.####.exr");
  const CliResult r = run_ssgi({"info", in, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["layout"]["name"], "blender");
  EXPECT_EQ(j["layout"]["channels"]["depth"][0], "ViewLayer.Depth.Z");
  EXPECT_EQ(j["frames"].size(), 6u);
  ASSERT_EQ(j["cameras"].size(), 6u);
  EXPECT_NEAR(j["cameras"][2]["hfov_deg"].get<double>(), 65.0, 1e-4);
  EXPECT_EQ(j["data_window"]["x_max"], 95);
  EXPECT_FALSE(j["plan"].empty());
  EXPECT_TRUE(j["error"].is_null());
  expect_usage_error(run_ssgi({"run", in, "-o", path("o.####.exr"), "--json"}), "run",
                     "'--json' is not an option of ssgi run (it is of ssgi info)");
}

TEST_F(Cli, InfoDetectsEveryLayoutPreset) {
  // The layout fixtures carry no camera, hence --fov (and -q: presets with world-space normals
  // warn that a --fov camera cannot turn them into camera space). Nuke's and Unreal's passes
  // include no direct light, so their plan cannot be made without --channel direct=: detected,
  // then exit 3.
  const std::vector<std::pair<std::string, int>> presets = {
      {"arnold", 0},   {"blender", 0},   {"karma", 0},  {"nuke", 3},
      {"redshift", 0}, {"renderman", 0}, {"unreal", 3}, {"vray", 0},
  };
  for (const auto& [preset, exit_code] : presets) {
    const std::string file = testdata("layouts/" + preset + ".exr");
    const CliResult r = run_ssgi({"info", file, "--fov", "60", "-q"});
    EXPECT_EQ(r.exit_code, exit_code) << preset << ": " << r.err;
    EXPECT_NE(r.out.find("\nlayout:        " + preset + " ("), std::string::npos) << preset << ":\n"
                                                                                  << r.out;
    if (exit_code == 0)
      EXPECT_EQ(r.err, "") << preset;
    else
      expect_one_error(r, file, "has no direct-light channels");
  }
}

TEST_F(Cli, ArbitraryChannelNamesWorkWithChannelFlags) {
  const std::string file = testdata("custom/custom.0001.exr");
  // No preset knows these names: exit 3, naming the file and the missing role.
  CliResult r = run_ssgi({"info", file});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, file, "no channel layout preset matches: no depth channel");
  // Named one by one, every role is found and the file runs.
  std::vector<std::string> args = {"info", file};
  args.insert(args.end(), kCustomChannelFlags.begin(), kCustomChannelFlags.end());
  r = run_ssgi(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\nlayout:        custom ("), std::string::npos);
  EXPECT_NE(r.out.find("  depth        dist\n"), std::string::npos);
  EXPECT_NE(r.out.find("  normal       nrm.x, nrm.y, nrm.z\n"), std::string::npos);
  EXPECT_NE(r.out.find("  albedo       base.r, base.g, base.b\n"), std::string::npos);
  args[0] = "run";
  args.insert(args.end(), {"-o", path("custom.####.exr"), "--rays", "2", "-q"});
  r = run_ssgi(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(entries(), std::set<std::string>{"custom.0001.exr"});
}

TEST_F(Cli, InfoCheckDecodesEveryFrameAsRunWould) {
  // What info alone passes (it reads headers) and run then fails on: a resolution change, a
  // truncated frame, an environment map that is not there. --check finds each, with run's
  // status.
  const CliResult plain = run_ssgi({"info", testdata("bad/resize.####.exr")});
  EXPECT_EQ(plain.exit_code, 0) << plain.err;
  const CliResult resize = run_ssgi({"info", testdata("bad/resize.####.exr"), "--check"});
  EXPECT_EQ(resize.exit_code, 3);
  EXPECT_NE(resize.out.find("check:         1 of 2 frames read as run reads them\n  frame 2      " +
                            testdata("bad/resize.0002.exr") + ": display window 32x24 differs"),
            std::string::npos)
      << resize.out;
  for (int f = 1; f <= 3; ++f)
    fs::copy_file(testdata("sample/sample.000" + std::to_string(f) + ".exr"),
                  path("in.000" + std::to_string(f) + ".exr"));
  {
    const std::string bytes = file_bytes(path("in.0002.exr"));
    std::ofstream(path("in.0002.exr"), std::ios::binary | std::ios::trunc)
        << bytes.substr(0, bytes.size() / 2);
  }
  const CliResult cut = run_ssgi({"info", path("in.####.exr"), "--check", "--json"});
  EXPECT_EQ(cut.exit_code, 4) << cut.err;
  const nlohmann::json j = nlohmann::json::parse(cut.out);
  EXPECT_EQ(j["check"]["frames"], 3);
  EXPECT_EQ(j["check"]["read"], 2);
  ASSERT_EQ(j["check"]["failed"].size(), 1u);
  EXPECT_EQ(j["check"]["failed"][0]["frame"], 2);
  EXPECT_EQ(j["error"].get<std::string>().rfind(path("in.0002.exr") + ": ", 0), 0u) << j["error"];
  expect_one_error(cut, path("in.0002.exr"), "");
  const CliResult env = run_ssgi(
      {"info", testdata("sample/sample.####.exr"), "--check", "--env", path("nowhere.exr")});
  EXPECT_EQ(env.exit_code, 4) << env.err;
  EXPECT_NE(env.out.find("6 of 6 frames read as run reads them; the environment map cannot be "
                         "used"),
            std::string::npos)
      << env.out;
  const CliResult ok = run_ssgi({"info", testdata("sample/sample.####.exr"), "--check"});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("check:         6 of 6 frames read as run reads them\n"),
            std::string::npos);
  // Each frame read says what the miss model decides for it (the room is enclosed all round).
  EXPECT_NE(ok.out.find("  frame 6      misses (auto): up "), std::string::npos) << ok.out;
  EXPECT_NE(ok.out.find("enclosed right left up down forward back: 1.00 1.00 1.00 1.00"),
            std::string::npos)
      << ok.out;
  // A sequence that cannot even be opened: --json still prints a document, the error.
  const CliResult none = run_ssgi({"info", path("nothing.####.exr"), "--json"});
  EXPECT_EQ(none.exit_code, 4);
  EXPECT_EQ(nlohmann::json::parse(none.out)["error"],
            path("nothing.####.exr") + ": no files match this pattern");
}

}  // namespace
}  // namespace cli_test
