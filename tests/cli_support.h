// What the end-to-end tests of the `ssgi` command line share: running the built binary,
// reading and writing EXRs as float planes, the fixtures, and a fresh directory per test.
#pragma once

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace cli_test {

namespace fs = std::filesystem;

inline const std::string kTestdata = SSGI_TESTDATA_DIR;

inline std::string testdata(const std::string& relative) { return kTestdata + "/" + relative; }

// What a finished `ssgi` process left: its exit code and both streams.
struct CliResult {
  int exit_code = -1;
  std::string out, err;

  std::vector<std::string> err_lines() const {
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  }
};

// Runs the built binary with `args` (no shell), capturing stdout and stderr through pipes that
// are drained together so that neither can fill up and block the child.
CliResult run_ssgi(const std::vector<std::string>& args);

// An EXR's first subimage: its header and every channel as a float plane.
struct ExrImage {
  OIIO::ImageSpec spec;
  std::map<std::string, std::vector<float>> planes;

  std::set<std::string> channel_names() const {
    return {spec.channelnames.begin(), spec.channelnames.end()};
  }
  OIIO::TypeDesc format_of(const std::string& channel) const {
    const auto it = std::find(spec.channelnames.begin(), spec.channelnames.end(), channel);
    return spec.channelformat(static_cast<int>(it - spec.channelnames.begin()));
  }
};

ExrImage read_exr(const std::string& path);

// Writes `image` (all channels float) to `path`.
void write_exr(const std::string& path, const ExrImage& image);

std::string file_bytes(const std::string& path);

// RMSE of `a`'s indirect light against `b`'s over surface pixels (input depth below 1e9),
// divided by the mean of `b`'s: the relRMSE of ssgi compare --metric relrmse.
double IndirectRelRmse(const ExrImage& a, const ExrImage& b, const std::string& depth_channel);

inline const std::vector<std::string> kOurChannels = {
    "R",          "G",    "B",    "A",    "indirect.R", "indirect.G",
    "indirect.B", "gi.R", "gi.G", "gi.B", "coverage.Y"};

// custom/ holds the sample under names no preset knows.
inline const std::vector<std::string> kCustomChannelFlags = {
    "--channel", "depth=dist",   "--channel", "normal=nrm",    "--channel", "albedo=base",
    "--channel", "direct=light", "--channel", "emission=glow", "--channel", "beauty=beauty"};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("ssgi_cli_test_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // The names in the test directory, hidden ones (temporary files) included.
  std::set<std::string> entries() const {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.insert(e.path().filename().string());
    return names;
  }

  // Asserts a failure reported as exactly the one line `ssgi: error: <file>: <what>`, with
  // `what` containing `phrase`; when it was a frame's (the run got to its frames), followed by
  // the run's summary saying that no frame was written.
  static void expect_one_error(const CliResult& r, const std::string& file,
                               const std::string& phrase) {
    std::vector<std::string> lines = r.err_lines();
    if (lines.size() == 2 && lines[1].rfind("ssgi: 0 of ", 0) == 0 &&
        lines[1].find(" frames written, ") != std::string::npos)
      lines.pop_back();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    const std::string head = "ssgi: error: " + file + ": ";
    EXPECT_EQ(lines[0].rfind(head, 0), 0u) << lines[0];
    EXPECT_NE(lines[0].find(phrase, head.size()), std::string::npos) << lines[0];
  }

  // Asserts a usage error: the error line and the hint, nothing else.
  static void expect_usage_error(const CliResult& r, const std::string& subcommand,
                                 const std::string& what) {
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(r.err, "ssgi: error: " + what + "\nTry 'ssgi " + subcommand + " --help'.\n");
  }

  // in.0001.exr .. in.000<count>.exr in the test directory: the sample's frames, but for frame
  // `broken`, which is not an image.
  void write_frames_with_a_broken_one(int count, int broken) const {
    for (int f = 1; f <= count; ++f) {
      const std::string name = "in.000" + std::to_string(f) + ".exr";
      if (f == broken)
        std::ofstream(path(name)) << "not an image";
      else
        fs::copy_file(testdata("sample/sample.000" + std::to_string(f) + ".exr"), path(name));
    }
  }

  fs::path dir_;
};

}  // namespace cli_test
