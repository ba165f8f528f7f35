// `ssgi info`: the report on a sequence (text and JSON), layout detection, channel flags,
// --check's decoding of every frame and the run's memory plan.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
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

// The memory line `ssgi run -v` logs, or info's first memory line: the estimated peak, its parts
// (run's only) and the limit, as text.
struct MemoryLine {
  std::string peak, parts, limit;
};

MemoryLine memory_line(const std::string& text) {
  static const std::regex run_line(
      R"(ssgi: memory: estimated peak ([^(\n]+) \((.*)\); limit (.*))");
  static const std::regex info_line(R"(\nmemory: +estimated peak ([^;\n]+); limit (.*))");
  std::smatch m;
  if (std::regex_search(text, m, run_line)) return {m[1], m[2], m[3]};
  if (std::regex_search(text, m, info_line)) return {m[1], "", m[2]};
  return {};
}

TEST_F(Cli, InfoPlansTheRunsMemoryAsRunDoes) {
  // Three frames of the sample on 2 threads: the estimate counts each worker. A limit far above
  // the estimate keeps a scheduler's out of the numbers.
  const std::string in = testdata("sample/sample.####.exr");
  const std::vector<std::string> common = {"--frames", "1-3", "--threads", "2"};
  const auto info = [&](const std::vector<std::string>& flags) {
    std::vector<std::string> args = {"info", in};
    args.insert(args.end(), common.begin(), common.end());
    args.insert(args.end(), flags.begin(), flags.end());
    return run_ssgi(args);
  };
  const auto info_json = [&](std::vector<std::string> flags) {
    flags.push_back("--json");
    const CliResult r = info(flags);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out)["memory"];
  };
  const auto bytes = [](const nlohmann::json& m) {
    return m["estimated_peak_bytes"].get<std::uint64_t>();
  };

  const nlohmann::json roomy = info_json({"--max-memory", "64G"});
  const std::uint64_t full = bytes(roomy);
  // At 96 x 64 the program and its 2 workers' stacks and buffers are most of it.
  EXPECT_GT(full, 64u << 20);
  EXPECT_LT(full, 1u << 30);
  EXPECT_EQ(roomy["limit"]["bytes"], std::uint64_t{64} << 30);
  EXPECT_EQ(roomy["limit"]["from"], "--max-memory");
  // Under a limit that fits it, the fastest plan: two frames in flight, each decoded once.
  EXPECT_EQ(roomy["frames_in_flight"], 2);
  EXPECT_EQ(roomy["frames_in_flight_asked"], 0);
  EXPECT_EQ(roomy["read_twice"], false);
  EXPECT_EQ(roomy["refused"], false);
  EXPECT_EQ(roomy["parts"].get<std::string>().find("read twice"), std::string::npos)
      << roomy["parts"];
  // Without passthrough the run holds no more (the passed-through channels are read from the
  // file a strip at a time when a frame is written); one frame at a time holds less.
  EXPECT_LE(bytes(info_json({"--max-memory", "64G", "--no-passthrough"})), full);
  const nlohmann::json one = info_json({"--max-memory", "64G", "--frames-in-flight", "1"});
  EXPECT_LT(bytes(one), full);
  EXPECT_EQ(one["frames_in_flight_asked"], 1);

  // A limit a byte below the estimate: the second frame in flight goes first, the frames are
  // still read once.
  const std::string below_full = std::to_string(full - 1);
  const nlohmann::json fewer = info_json({"--max-memory", below_full});
  EXPECT_EQ(fewer["frames_in_flight"], 1);
  EXPECT_EQ(fewer["frames_in_flight_asked"], 0);
  EXPECT_EQ(fewer["read_twice"], false);
  EXPECT_EQ(fewer["refused"], false);
  EXPECT_LT(bytes(fewer), full);
  EXPECT_EQ(bytes(fewer), bytes(one));
  // A byte below that: the two waiting frames' passes go, read twice.
  const std::string below_fewer = std::to_string(bytes(fewer) - 1);
  const nlohmann::json twice = info_json({"--max-memory", below_fewer});
  EXPECT_EQ(twice["frames_in_flight"], 1);
  EXPECT_EQ(twice["read_twice"], true);
  EXPECT_EQ(twice["refused"], false);
  EXPECT_LT(bytes(twice), bytes(fewer));
  EXPECT_NE(twice["parts"].get<std::string>().find("read twice"), std::string::npos)
      << twice["parts"];
  // A byte below the least the run can hold: refused by run, reported by info (exit 0).
  const std::string below_twice = std::to_string(bytes(twice) - 1);
  EXPECT_EQ(info_json({"--max-memory", below_twice})["refused"], true);

  // The text says the same.
  CliResult r = info({"--max-memory", below_full});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MemoryLine line = memory_line(r.out);
  EXPECT_EQ(line.peak, fewer["estimated_peak"]) << r.out;
  EXPECT_NE(line.limit.find("iB from --max-memory"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" from --max-memory\n  parts          " + fewer["parts"].get<std::string>() +
                       "\n  in flight      1 frame read, lit and written at once (to fit the "
                       "limit)\n  decoded        once a frame\n"),
            std::string::npos)
      << r.out;
  r = info({"--max-memory", below_fewer});
  EXPECT_NE(r.out.find("\n  decoded        twice a frame (lit, then finished and written)\n"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("\n  refused"), std::string::npos) << r.out;
  r = info({"--max-memory", below_twice});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      r.out.find("\n  refused        over the limit: ssgi run would refuse the run (exit 3)\n"),
      std::string::npos)
      << r.out;

  // run -v logs the same plan for the same options: the estimate, its parts and the limit (the
  // scheduler's or none when no --max-memory is given), and the fewer frames or the second
  // reading; over the limit it refuses with the estimate info gave.
  const std::vector<std::vector<std::string>> cases = {
      {}, {"--no-passthrough"}, {"--max-memory", below_full}, {"--max-memory", below_fewer}};
  for (const std::vector<std::string>& flags : cases) {
    std::string what;
    for (const std::string& f : flags) what += f + " ";
    const nlohmann::json planned = info_json(flags);
    const MemoryLine info_text = memory_line(info(flags).out);
    std::vector<std::string> args = {"run", in, "-o", path("o.####.exr"), "-v"};
    args.insert(args.end(), common.begin(), common.end());
    args.insert(args.end(), flags.begin(), flags.end());
    const CliResult ran = run_ssgi(args);
    ASSERT_EQ(ran.exit_code, 0) << what << ran.err;
    const MemoryLine logged = memory_line(ran.err);
    ASSERT_FALSE(logged.peak.empty()) << what << ran.err;
    EXPECT_EQ(logged.peak, planned["estimated_peak"]) << what;
    EXPECT_EQ(logged.parts, planned["parts"]) << what;
    EXPECT_EQ(logged.peak, info_text.peak) << what;
    EXPECT_EQ(logged.limit, info_text.limit) << what;
    EXPECT_EQ(ran.err.find("memory: 1 frame in flight") != std::string::npos,
              planned["frames_in_flight"] == 1)
        << what << ran.err;
    EXPECT_EQ(ran.err.find("each frame written decoded twice") != std::string::npos,
              planned["read_twice"] == true)
        << what << ran.err;
  }
  std::vector<std::string> args = {"run",          in,         "-o", path("o.####.exr"),
                                   "--max-memory", below_twice};
  args.insert(args.end(), common.begin(), common.end());
  const CliResult refused = run_ssgi(args);
  EXPECT_EQ(refused.exit_code, 3);
  expect_one_error(refused, testdata("sample/sample.0001.exr"),
                   "the run needs an estimated " + twice["estimated_peak"].get<std::string>() +
                       " (" + twice["parts"].get<std::string>() + "), over the limit of ");
}

}  // namespace
}  // namespace cli_test
