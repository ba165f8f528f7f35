// Which frames `ssgi run` writes (--frames, ranges in the name, the frames on disk) and how a
// frame that cannot be read or written fails: its exit code, one line, nothing half-written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

TEST_F(Cli, FramesOptionAndRangeInNameSelectFramesToWrite) {
  CliResult r = run_ssgi({"run", testdata("sample/sample.####.exr"), "--frames", "2-4", "-o",
                          path("a.####.exr"), "--rays", "2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(entries(), (std::set<std::string>{"a.0002.exr", "a.0003.exr", "a.0004.exr"}));
  fs::remove_all(dir_);
  fs::create_directories(dir_);
  r = run_ssgi(
      {"run", testdata("sample/sample.2-3#.exr"), "-o", path("b.%04d.exr"), "--rays", "2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(entries(), (std::set<std::string>{"b.0002.exr", "b.0003.exr"}));
}

TEST_F(Cli, MissingFrameInRangeFailsBeforeWritingAnything) {
  const std::string in = testdata("bad/gap.####.exr");
  // Frames are resolved before any is processed: exit 4 naming frame 2, nothing written.
  CliResult r = run_ssgi({"run", in, "--frames", "1-3", "-o", path("g.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(r, testdata("bad/gap.0002.exr"), "frame 2 is missing");
  EXPECT_TRUE(entries().empty());
  // The same range in the name.
  r = run_ssgi({"run", testdata("bad/gap.1-3#.exr"), "-o", path("g.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(r, testdata("bad/gap.0002.exr"), "frame 2 is missing");
  EXPECT_TRUE(entries().empty());
  // --skip-missing: the others are written, with one warning naming the missing one.
  r = run_ssgi(
      {"run", in, "--frames", "1-3", "--skip-missing", "-o", path("g.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  ASSERT_FALSE(r.err_lines().empty());
  EXPECT_EQ(r.err_lines()[0],
            "ssgi: warning: " + testdata("bad/gap.0002.exr") + ": frame 2 is missing; skipped");
  // + 2 progress lines and the summary
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 4) << r.err;
  EXPECT_EQ(r.err_lines().back(), "ssgi: 2 of 2 frames written");
  EXPECT_EQ(entries(), (std::set<std::string>{"g.0001.exr", "g.0003.exr"}));
}

TEST_F(Cli, WithoutARangeTheFramesOnDiskAreWritten) {
  // oiiotool's rule: a pattern alone means the frames that exist, so a gap is not an error.
  const CliResult r = run_ssgi(
      {"run", testdata("bad/gap.####.exr"), "-o", path("g.####.exr"), "--rays", "2", "-q"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(entries(), (std::set<std::string>{"g.0001.exr", "g.0003.exr"}));
}

// Whether two EXRs hold the same bits in each of our channels (memcmp: signed zeros too).
bool same_bits(const std::string& a, const std::string& b) {
  const ExrImage x = read_exr(a), y = read_exr(b);
  for (const std::string& c : kOurChannels) {
    const std::vector<float>& p = x.planes.at(c);
    const std::vector<float>& q = y.planes.at(c);
    if (p.size() != q.size() || std::memcmp(p.data(), q.data(), p.size() * sizeof(float)) != 0)
      return false;
  }
  return true;
}

TEST_F(Cli, AGapInTheFramesOnDiskIsWarnedAboutAndEndsTheShot) {
  // The sample without frame 3, and each side of the gap as a shot of its own.
  for (const auto& [dir, frames] : std::vector<std::pair<std::string, std::vector<int>>>{
           {"in", {1, 2, 4, 5, 6}}, {"before", {1, 2}}, {"after", {4, 5, 6}}}) {
    fs::create_directory(path(dir));
    for (int f : frames) {
      const std::string name = "sample.000" + std::to_string(f) + ".exr";
      fs::copy_file(testdata("sample/" + name), path(dir + "/" + name));
    }
  }
  const std::string in = path("in/sample.####.exr");
  const std::string warning = "ssgi: warning: " + in +
                              ": frame 3 is missing; the temporal stage ends the shot at the gap, "
                              "as at its first and last frames";
  const std::vector<int> written = {1, 2, 4, 5, 6};
  for (const std::string temporal : {"window", "ema"}) {
    SCOPED_TRACE(temporal);
    const std::vector<std::string> settings = {"--preset", "draft", "--temporal", temporal};
    auto run = [&](std::vector<std::string> args) {
      args.insert(args.end(), settings.begin(), settings.end());
      return run_ssgi(args);
    };
    const CliResult r = run({"run", in, "-o", path(temporal + ".####.exr")});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::vector<std::string> lines = r.err_lines();
    ASSERT_EQ(lines.size(), 7u) << r.err;  // the warning, 5 frames, the summary
    EXPECT_EQ(lines.front(), warning);
    EXPECT_EQ(lines.back(), "ssgi: 5 of 5 frames written");
    // Each side as its own shot: frame 2's window and average never see frame 4, nor 4's 2.
    for (const std::string side : {"before", "after"})
      ASSERT_EQ(run({"run", path(side + "/sample.####.exr"), "-o", path(temporal + "_own.####.exr"),
                     "-q"})
                    .exit_code,
                0);
    // Chunks that start right after the gap and end right before it, and one frame alone.
    ASSERT_EQ(run({"run", in, "--frames", "4-5", "-o", path(temporal + "_chunk.####.exr"), "-q"})
                  .exit_code,
              0);
    ASSERT_EQ(run({"run", in, "--frames", "1-2,6", "-o", path(temporal + "_chunk.####.exr"), "-q"})
                  .exit_code,
              0);
    ASSERT_EQ(
        run({"run", path("in/sample.0004.exr"), "-o", path(temporal + "_single.0004.exr"), "-q"})
            .exit_code,
        0);
    for (int f : written) {
      const std::string frame = ".000" + std::to_string(f) + ".exr";
      const std::string whole = path(temporal + frame);
      EXPECT_TRUE(same_bits(whole, path(temporal + "_own" + frame))) << "frame " << f;
      EXPECT_TRUE(same_bits(whole, path(temporal + "_chunk" + frame))) << "frame " << f;
    }
    EXPECT_TRUE(same_bits(path(temporal + ".0004.exr"), path(temporal + "_single.0004.exr")));
  }
  // info and sweep say it too, once (sweep runs the shot several times).
  CliResult r = run_ssgi({"info", in});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, warning + "\n");
  r = run_ssgi(
      {"sweep", in, "-o", path("sweep.csv"), "--presets", "draft", "--reference-spp", "4"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = r.err_lines();
  EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                          [](const std::string& l) { return l.rfind("ssgi: warning: ", 0) == 0; }),
            1)
      << r.err;
  EXPECT_EQ(lines.front(), warning);
  // Asked for by --frames, the missing frame is an error.
  r = run_ssgi({"run", in, "--frames", "1-6", "-o", path("listed.####.exr")});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(r, path("in/sample.0003.exr"), "frame 3 is missing");
  EXPECT_FALSE(fs::exists(path("listed.0001.exr")));
}

TEST_F(Cli, PatternMatchingNothingIsAnError) {
  // Never a silent success with zero frames.
  const std::string in = testdata("sample/nothing.####.exr");
  const CliResult r = run_ssgi({"run", in, "-o", path("o.####.exr")});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(r, in, "no files match this pattern");
  EXPECT_TRUE(entries().empty());
}

TEST_F(Cli, BadInputsGiveTheirExitCodeOneLineAndNoOutput) {
  struct Case {
    std::string file;
    int exit_code;
    std::string phrase;
  };
  // 4: the file cannot be read as an EXR at all; 3: it reads but cannot be used.
  const std::vector<Case> cases = {
      {"bad/missing.0001.exr", 4, "no such file"},
      {"bad/truncated.exr", 4, "cannot read pixels"},
      {"bad/notexr.exr", 4, "is not an OpenEXR file"},
      {"bad/empty.exr", 4, "empty file"},
      {"bad/nodepth.0001.exr", 3, "no depth channel"},
  };
  for (const Case& c : cases) {
    const std::string in = testdata(c.file);
    const CliResult r = run_ssgi({"run", in, "-o", path("o.exr"), "--rays", "2"});
    EXPECT_EQ(r.exit_code, c.exit_code) << c.file << ": " << r.err;
    expect_one_error(r, in, c.phrase);
    EXPECT_TRUE(entries().empty()) << c.file;
  }
}

TEST_F(Cli, ResolutionChangeFailsThatFrameOnly) {
  // Frame 1 is written; frame 2 (32x24 after 48x32) fails alone: exit 1, "some frames failed".
  // Frame 1's temporal window leaves frame 2 out, with a warning.
  const CliResult r =
      run_ssgi({"run", testdata("bad/resize.####.exr"), "-o", path("r.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 1);
  const std::vector<std::string> lines = r.err_lines();
  const std::string why = "display window 32x24 differs from the first frame's 48x32";
  ASSERT_EQ(lines.size(), 4u) << r.err;
  EXPECT_EQ(lines[3], "ssgi: 1 of 2 frames written, 1 failed (2)");
  EXPECT_EQ(lines[0], "ssgi: warning: " + testdata("bad/resize.0002.exr") + ": " + why +
                          "; left out of the temporal window");
  EXPECT_EQ(lines[1].rfind("ssgi: frame 1 (1/2): ", 0), 0u);
  EXPECT_EQ(lines[2], "ssgi: error: " + testdata("bad/resize.0002.exr") + ": " + why);
  EXPECT_EQ(entries(), std::set<std::string>{"r.0001.exr"});
}

TEST_F(Cli, FailFastStopsAtTheFirstFrameThatFails) {
  // Frame 2 of 3 is not an EXR. By default frames 1 and 3 are written (exit 1); with
  // --fail-fast the run stops there, with that frame's status (4), and frame 3 is not tried.
  write_frames_with_a_broken_one(3, 2);
  const std::vector<std::string> args = {
      "run", path("in.####.exr"), "--rays", "2", "--temporal", "none", "-q", "-o"};
  std::vector<std::string> all = args;
  all.push_back(path("all.####.exr"));
  const CliResult r = run_ssgi(all);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(fs::exists(path("all.0001.exr")));
  EXPECT_TRUE(fs::exists(path("all.0003.exr")));
  std::vector<std::string> fast = args;
  fast.push_back(path("fast.####.exr"));
  fast.push_back("--fail-fast");
  const CliResult f = run_ssgi(fast);
  EXPECT_EQ(f.exit_code, 4) << f.err;
  EXPECT_TRUE(fs::exists(path("fast.0001.exr")));
  EXPECT_FALSE(fs::exists(path("fast.0002.exr")));
  EXPECT_FALSE(fs::exists(path("fast.0003.exr")));
  expect_one_error(f, path("in.0002.exr"), "");
  // Not quiet: the last line counts what was written, failed and not attempted.
  std::vector<std::string> loud = {"run", path("in.####.exr"),   "--rays",
                                   "2",   "--temporal",          "none",
                                   "-o",  path("loud.####.exr"), "--fail-fast"};
  const CliResult l = run_ssgi(loud);
  EXPECT_EQ(l.exit_code, 4) << l.err;
  ASSERT_FALSE(l.err_lines().empty());
  EXPECT_EQ(l.err_lines().back(),
            "ssgi: 1 of 3 frames written, 1 failed (2), 1 not attempted (--fail-fast)");
}

TEST_F(Cli, UnwritableOutputFailsOnceWithoutTemporaryFiles) {
  const std::string in = testdata("sample/sample.####.exr");
  std::ofstream(path("file")) << "x";
  // A directory that is a regular file, below it or as it: checked before any frame is
  // computed, so one line, not one per frame.
  CliResult r = run_ssgi({"run", in, "-o", path("file/o.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(
      r, path("file/o.0001.exr"),
      "output directory " + path("file") + ": " + path("file") + " is not a directory");
  r = run_ssgi({"run", in, "-o", path("file/sub/o.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(
      r, path("file/sub/o.0001.exr"),
      "output directory " + path("file/sub") + ": " + path("file") + " is not a directory");
  EXPECT_EQ(entries(), std::set<std::string>{"file"});
  // Missing output folders are made, as mkdir -p would.
  r = run_ssgi({"run", testdata("sample/sample.0001.exr"), "-o", path("new/shot/o.####.exr"),
                "--rays", "2", "-q"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(path("new/shot/o.0001.exr")));
  fs::remove_all(path("new"));
  // The target name is taken by a directory: the frame is written to a temporary file, the
  // rename fails, and the temporary file is removed.
  fs::create_directory(path("o.0001.exr"));
  r = run_ssgi(
      {"run", testdata("sample/sample.0001.exr"), "-o", path("o.####.exr"), "--rays", "2"});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(r, path("o.0001.exr"),
                   "cannot move the finished frame into place: Is a directory");
  EXPECT_EQ(entries(), (std::set<std::string>{"file", "o.0001.exr"}));
  EXPECT_TRUE(fs::is_empty(path("o.0001.exr")));
}

TEST_F(Cli, RefusesToOverwriteAnInputFrame) {
  for (const char* f : {"sample.0001.exr", "sample.0002.exr"})
    fs::copy_file(testdata(std::string("sample/") + f), path(f));
  const std::string before = file_bytes(path("sample.0001.exr"));
  // The same file however the output is spelled: same pattern, %04d, a detour through "..";
  // the error names the output as spelled.
  const std::string detour = (dir_ / ".." / dir_.filename()).string();
  const std::vector<std::pair<std::string, std::string>> outputs = {
      {path("sample.####.exr"), path("sample.0001.exr")},
      {path("sample.%04d.exr"), path("sample.0001.exr")},
      {detour + "/sample.####.exr", detour + "/sample.0001.exr"},
  };
  for (const auto& [out, first] : outputs) {
    const CliResult r = run_ssgi({"run", path("sample.####.exr"), "-o", out, "--rays", "2"});
    EXPECT_EQ(r.exit_code, 2) << out;
    EXPECT_EQ(r.err, "ssgi: error: " + first +
                         ": output would overwrite input frame 1\nTry 'ssgi run --help'.\n");
  }
  EXPECT_EQ(file_bytes(path("sample.0001.exr")), before);
  EXPECT_EQ(entries(), (std::set<std::string>{"sample.0001.exr", "sample.0002.exr"}));
}

TEST_F(Cli, AnUnreadableNeighbourIsWarnedAboutOnce) {
  // Frame 3 of 5 is not an EXR: it fails alone, and the four windows it falls in (+-2) leave it
  // out with one warning between them, not one each.
  write_frames_with_a_broken_one(5, 3);
  const CliResult r = run_ssgi({"run", path("in.####.exr"), "-o", path("o.####.exr"), "--preset",
                                "draft", "--progress", "lines"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  int warnings = 0, errors = 0;
  for (const std::string& line : r.err_lines()) {
    warnings += line.rfind("ssgi: warning: " + path("in.0003.exr") + ": ", 0) == 0 &&
                line.find("left out of the temporal window") != std::string::npos;
    errors += line.rfind("ssgi: error: " + path("in.0003.exr") + ": ", 0) == 0;
  }
  EXPECT_EQ(warnings, 1) << r.err;
  EXPECT_EQ(errors, 1) << r.err;
  EXPECT_EQ(r.err_lines().back(), "ssgi: 4 of 5 frames written, 1 failed (3)");
}

}  // namespace
}  // namespace cli_test
