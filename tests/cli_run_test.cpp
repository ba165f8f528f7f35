// What `ssgi run` writes: its layers, the input's channels, parts, windows and metadata, the
// output options (--no-passthrough, --layer-prefix, --datatype, --compression), region renders
// with their context, and the statistics file.
#include <Imath/half.h>
#include <OpenImageIO/imagebufalgo.h>
#include <fcntl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

// Every fixture sequence: the pattern under testdata/ and extra flags it needs.
struct Fixture {
  std::string pattern;
  std::vector<std::string> flags;
};

const std::vector<Fixture> kSceneFixtures = {
    {"sample/sample.####.exr", {}},
    {"static/static.####.exr", {"--frames", "1-3"}},
    {"pan/pan.####.exr", {"--frames", "1-3"}},
    {"moving/moving.####.exr", {"--frames", "1-3"}},
    {"furnace/furnace.0001.exr", {}},
    {"plane/plane.0001.exr", {}},
    {"symmetric/symmetric.0001.exr", {}},
    {"overscan/overscan.0001.exr", {}},
    {"crop/crop.0001.exr", {}},
    {"custom/custom.0001.exr", kCustomChannelFlags},
    {"bad/nan.0001.exr", {}},
};

TEST_F(Cli, RunWritesOurLayersInputChannelsAndMetadata) {
  const CliResult r = run_ssgi({"run", testdata("sample/sample.####.exr"), "-o",
                                path("out.####.exr"), "--rays", "2", "--seed", "7"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Not a terminal: one progress line per frame, then the summary.
  EXPECT_EQ(r.err_lines().size(), 7u) << r.err;
  EXPECT_EQ(r.err_lines().back(), "ssgi: 6 of 6 frames written");
  EXPECT_EQ(r.err_lines()[0].rfind("ssgi: frame 1 (1/6): ", 0), 0u);
  EXPECT_EQ(entries(), (std::set<std::string>{"out.0001.exr", "out.0002.exr", "out.0003.exr",
                                              "out.0004.exr", "out.0005.exr", "out.0006.exr"}));
  for (int f = 1; f <= 6; ++f) {
    const std::string name = "sample.000" + std::to_string(f) + ".exr";
    const ExrImage in = read_exr(testdata("sample/" + name));
    const ExrImage out = read_exr(path("out.000" + std::to_string(f) + ".exr"));
    // Ours plus every input channel, the latter with unchanged pixels.
    std::set<std::string> expected = in.channel_names();
    expected.insert(kOurChannels.begin(), kOurChannels.end());
    EXPECT_EQ(out.channel_names(), expected);
    for (const auto& [channel, plane] : in.planes)
      EXPECT_EQ(out.planes.at(channel), plane) << channel;
    for (const std::string& c : kOurChannels)
      EXPECT_EQ(out.format_of(c), OIIO::TypeDesc::FLOAT) << c;
    // Coverage within [0, 1], 0 on background; this interior's surfaces get part of their light
    // from the miss model and part from traced rays.
    const auto& coverage = out.planes.at("coverage.Y");
    const auto& depth = in.planes.at("ViewLayer.Depth.Z");
    double on_surfaces = 0;
    int surfaces = 0;
    for (std::size_t i = 0; i < coverage.size(); ++i) {
      ASSERT_TRUE(coverage[i] >= 0.0f && coverage[i] <= 1.0f) << coverage[i];
      if (!(depth[i] < 1e9f)) {
        EXPECT_EQ(coverage[i], 0.0f);
        continue;
      }
      on_surfaces += coverage[i];
      ++surfaces;
    }
    EXPECT_GT(on_surfaces / surfaces, 0.1);
    EXPECT_LT(on_surfaces / surfaces, 0.9);
    // Cameras and Blender's attributes kept; provenance added.
    for (const char* attr : {"worldToCamera", "worldToNDC", "BlenderMultiChannel", "Frame"}) {
      const OIIO::ParamValue* a = in.spec.find_attribute(attr);
      const OIIO::ParamValue* b = out.spec.find_attribute(attr);
      ASSERT_TRUE(a && b) << attr;
      EXPECT_EQ(a->type(), b->type()) << attr;
      EXPECT_EQ(std::memcmp(a->data(), b->data(), a->type().size()), 0) << attr;
    }
    EXPECT_EQ(out.spec.get_string_attribute("ssgi:seed"), "7");
    EXPECT_FALSE(out.spec.get_string_attribute("ssgi:version").empty());
    // As std::string: OIIO 2.4's string_view::rfind(s, 0) never matches at 0.
    const std::string command_line = out.spec.get_string_attribute("ssgi:commandLine");
    EXPECT_EQ(command_line.rfind("ssgi run ", 0), 0u) << command_line;
    EXPECT_EQ(out.spec.get_string_attribute("compression"), "zip");
  }
}

TEST_F(Cli, DataAndDisplayWindowsAreKept) {
  // Overscan (data larger than display), a crop (smaller) and the plain case.
  for (const std::string name :
       {"overscan/overscan.0001.exr", "crop/crop.0001.exr", "sample/sample.0001.exr"}) {
    const std::string out = path("out.exr");
    const CliResult r = run_ssgi({"run", testdata(name), "-o", out, "--rays", "2", "-q"});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    const OIIO::ImageSpec in = read_exr(testdata(name)).spec;
    const OIIO::ImageSpec got = read_exr(out).spec;
    EXPECT_EQ(std::vector<int>({got.x, got.y, got.width, got.height}),
              std::vector<int>({in.x, in.y, in.width, in.height}))
        << name;
    EXPECT_EQ(std::vector<int>({got.full_x, got.full_y, got.full_width, got.full_height}),
              std::vector<int>({in.full_x, in.full_y, in.full_width, in.full_height}))
        << name;
  }
}

// A region render (a data window inside the display window) lacks what lies around it: alone it
// gets a fraction of the whole frame's light there; with the whole shot as --context it gets the
// light the whole frame gets over its pixels, bit for bit, in the temporal window too, and writes
// its own window and channels.
TEST_F(Cli, ARegionRenderWithItsContextGetsTheWholeFramesLight) {
  const OIIO::ROI region(24, 72, 16, 48);  // the centre quarter of the 96x64 display window
  for (int f = 1; f <= 6; ++f) {
    const std::string n = "000" + std::to_string(f);
    const OIIO::ImageBuf whole(testdata("sample/sample." + n + ".exr"));
    const OIIO::ImageBuf crop = OIIO::ImageBufAlgo::crop(whole, region);
    ASSERT_TRUE(crop.write(path("crop." + n + ".exr"))) << crop.geterror();
  }
  const std::string whole_pattern = testdata("sample/sample.####.exr");
  ASSERT_EQ(run_ssgi({"run", whole_pattern, "-o", path("whole.####.exr"), "-q"}).exit_code, 0);
  ASSERT_EQ(run_ssgi({"run", path("crop.####.exr"), "-o", path("alone.####.exr"), "-q"}).exit_code,
            0);
  const CliResult r = run_ssgi({"run", path("crop.####.exr"), "--context", whole_pattern, "-o",
                                path("region.####.exr"), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  double alone_sum = 0, whole_sum = 0;
  for (int f = 1; f <= 6; ++f) {
    const std::string n = "000" + std::to_string(f);
    const ExrImage whole = read_exr(path("whole." + n + ".exr"));
    const ExrImage alone = read_exr(path("alone." + n + ".exr"));
    const ExrImage got = read_exr(path("region." + n + ".exr"));
    const ExrImage input = read_exr(path("crop." + n + ".exr"));
    EXPECT_EQ(std::vector<int>({got.spec.x, got.spec.y, got.spec.width, got.spec.height,
                                got.spec.full_width, got.spec.full_height}),
              std::vector<int>({24, 16, 48, 32, 96, 64}));
    for (const std::string& c : input.spec.channelnames)
      EXPECT_EQ(got.planes.at(c), input.planes.at(c)) << "frame " << f << ", input's " << c;
    for (const std::string& c : kOurChannels) {
      const std::vector<float>& full = whole.planes.at(c);
      const std::vector<float>& mine = got.planes.at(c);
      ASSERT_EQ(mine.size(), 48u * 32u);
      int differ = 0;
      for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 48; ++x) differ += mine[y * 48 + x] != full[(y + 16) * 96 + x + 24];
      EXPECT_EQ(differ, 0) << "frame " << f << ", " << c;
    }
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 48; ++x) {
        alone_sum += alone.planes.at("indirect.G")[y * 48 + x];
        whole_sum += whole.planes.at("indirect.G")[(y + 16) * 96 + x + 24];
      }
  }
  // The crop alone lacks the walls around it: under half the whole frame's light there.
  EXPECT_GT(whole_sum, 0.1 * 6 * 48 * 32);
  EXPECT_LT(alone_sum, 0.5 * whole_sum);

  // One frame re-rendered alone: its temporal window's neighbours come from the context.
  fs::create_directory(path("lone"));
  fs::copy_file(path("crop.0003.exr"), path("lone/fix.0003.exr"));
  const CliResult lone = run_ssgi({"run", path("lone/fix.0003.exr"), "--context", whole_pattern,
                                   "-o", path("lone/out.####.exr"), "-v"});
  ASSERT_EQ(lone.exit_code, 0) << lone.err;
  EXPECT_NE(lone.err.find("temporal: symmetric window"), std::string::npos) << lone.err;
  const ExrImage whole = read_exr(path("whole.0003.exr"));
  const ExrImage got = read_exr(path("lone/out.0003.exr"));
  for (const std::string& c : kOurChannels) {
    int differ = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 48; ++x)
        differ += got.planes.at(c)[y * 48 + x] != whole.planes.at(c)[(y + 16) * 96 + x + 24];
    EXPECT_EQ(differ, 0) << "a lone frame, " << c;
  }
}

// A region render run alone is warned about, suggesting --context, and gets no more than the
// whole frame's light over its pixels. The region is the centre of `moving`, a floor and wall lit
// by a spot, whose surroundings are dark (as the Cycles stage's): its misses must not bring the
// lit centre's light in place of the dark border it cannot see, which would light it brighter
// than the whole frame does. One frame, whole and cropped, so that neither has temporal
// neighbours.
TEST_F(Cli, ARegionRenderAloneIsWarnedAndGetsNoMoreThanTheWholeFramesLight) {
  const OIIO::ROI region(16, 48, 8, 40);  // 32x32 at (16, 8) of the 64x48 display window
  fs::copy_file(testdata("moving/moving.0001.exr"), path("whole.0001.exr"));
  ASSERT_TRUE(OIIO::ImageBufAlgo::crop(OIIO::ImageBuf(path("whole.0001.exr")), region)
                  .write(path("crop.0001.exr")));
  const auto warnings = [](const CliResult& r) {
    std::vector<std::string> lines;
    for (const std::string& line : r.err_lines())
      if (line.rfind("ssgi: warning: ", 0) == 0) lines.push_back(line);
    return lines;
  };
  const CliResult whole = run_ssgi({"run", path("whole.0001.exr"), "-o", path("whole_out.exr")});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_EQ(warnings(whole).size(), 0u) << whole.err;
  const CliResult alone = run_ssgi({"run", path("crop.0001.exr"), "-o", path("alone.exr")});
  ASSERT_EQ(alone.exit_code, 0) << alone.err;

  // Per channel, the mean over the region's surface pixels.
  const ExrImage input = read_exr(path("crop.0001.exr"));
  const ExrImage alone_out = read_exr(path("alone.exr"));
  const ExrImage whole_out = read_exr(path("whole_out.exr"));
  for (const std::string c : {"R", "G", "B"}) {
    double alone_sum = 0, whole_sum = 0;
    int surfaces = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        if (!(input.planes.at("ViewLayer.Depth.Z")[y * 32 + x] < 1e9f)) continue;
        alone_sum += alone_out.planes.at("indirect." + c)[y * 32 + x];
        whole_sum += whole_out.planes.at("indirect." + c)[(y + 8) * 64 + x + 16];
        ++surfaces;
      }
    ASSERT_GT(surfaces, 0);
    const double alone_mean = alone_sum / surfaces, whole_mean = whole_sum / surfaces;
    // The whole frame's light there is about 0.065.
    EXPECT_GT(whole_mean, 0.03) << c;
    // At most 10% more (what a crop's own trace and denoising may add), and a clear fraction:
    // a crop whose rays bring nothing fails.
    EXPECT_LE(alone_mean, 1.10 * whole_mean) << c;
    EXPECT_GT(alone_mean, 0.5 * whole_mean) << c;
  }

  // One warning line, from run and from info, naming the file and suggesting --context.
  for (const CliResult& r : {alone, run_ssgi({"info", path("crop.0001.exr")})}) {
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::vector<std::string> lines = warnings(r);
    ASSERT_EQ(lines.size(), 1u) << r.err;
    const std::string head = "ssgi: warning: " + path("crop.0001.exr") +
                             ": the data window (16,8)-(47,39) is a region of the display window "
                             "(0,0)-(63,47): ";
    EXPECT_EQ(lines[0].rfind(head, 0), 0u) << lines[0];
    EXPECT_NE(lines[0].find("--context"), std::string::npos) << lines[0];
  }
  // With the whole frame as its context there is nothing to warn about.
  const CliResult with_context = run_ssgi({"run", path("crop.0001.exr"), "--context",
                                           path("whole.0001.exr"), "-o", path("region.exr")});
  ASSERT_EQ(with_context.exit_code, 0) << with_context.err;
  EXPECT_EQ(warnings(with_context).size(), 0u) << with_context.err;
}

// A context that is not the region's whole picture is refused before anything is written, with
// the context's file named.
TEST_F(Cli, AContextThatDoesNotHoldTheRegionIsRefused) {
  const OIIO::ImageBuf sample(testdata("sample/sample.0001.exr"));
  // Another display window.
  OIIO::ImageBuf other = sample;
  other.set_full(0, 95, 0, 63 + 8, 0, 0);
  ASSERT_TRUE(other.write(path("taller.0001.exr")));
  // A data window beside the region's.
  ASSERT_TRUE(
      OIIO::ImageBufAlgo::crop(sample, OIIO::ROI(0, 24, 0, 16)).write(path("corner.0001.exr")));
  for (const auto& [context, phrase] :
       {std::pair{path("taller.0001.exr"), "display window"},
        std::pair{path("corner.0001.exr"), "does not hold the input's (24,16)-(71,47)"}}) {
    const CliResult r = run_ssgi(
        {"run", testdata("crop/crop.0001.exr"), "--context", context, "-o", path("out.0001.exr")});
    EXPECT_EQ(r.exit_code, 3) << r.err;
    expect_one_error(r, context, phrase);
    EXPECT_FALSE(fs::exists(path("out.0001.exr")));
  }
  // Without a pass the region has.
  {
    std::vector<int> keep;
    std::vector<std::string> names;
    for (int c = 0; c < sample.nchannels(); ++c) {
      const std::string name = sample.spec().channel_name(c);
      if (name.find(".Emit.") != std::string::npos) continue;
      keep.push_back(c);
      names.push_back(name);
    }
    const OIIO::ImageBuf dark =
        OIIO::ImageBufAlgo::channels(sample, static_cast<int>(keep.size()), keep, {}, names);
    ASSERT_TRUE(dark.write(path("dark.0001.exr"))) << dark.geterror();
    const CliResult r = run_ssgi({"run", testdata("crop/crop.0001.exr"), "--context",
                                  path("dark.0001.exr"), "-o", path("out.0001.exr")});
    EXPECT_EQ(r.exit_code, 3) << r.err;
    expect_one_error(r, path("dark.0001.exr"), "has no emission channels, which the input has");
    EXPECT_FALSE(fs::exists(path("out.0001.exr")));
  }
  // Another frame of a panning shot: its camera is not the region's.
  fs::copy_file(testdata("pan/pan.0003.exr"), path("moved.0001.exr"));
  ASSERT_TRUE(OIIO::ImageBufAlgo::crop(OIIO::ImageBuf(testdata("pan/pan.0001.exr")),
                                       OIIO::ROI(8, 40, 8, 40))
                  .write(path("pan_crop.0001.exr")));
  const CliResult moved = run_ssgi({"run", path("pan_crop.0001.exr"), "--context",
                                    path("moved.0001.exr"), "-o", path("out.0001.exr")});
  EXPECT_EQ(moved.exit_code, 3) << moved.err;
  expect_one_error(moved, path("moved.0001.exr"), "camera is not the input's frame 1 camera");
  EXPECT_FALSE(fs::exists(path("out.0001.exr")));
  const CliResult missing = run_ssgi({"run", testdata("crop/crop.0001.exr"), "--context",
                                      path("none.####.exr"), "-o", path("out.0001.exr")});
  EXPECT_EQ(missing.exit_code, 4) << missing.err;
  expect_one_error(missing, path("none.0001.exr"), "missing");
  EXPECT_FALSE(fs::exists(path("out.0001.exr")));
}

TEST_F(Cli, NoPassthroughWritesOnlyOurChannels) {
  const CliResult r = run_ssgi({"run", testdata("sample/sample.0001.exr"), "-o", path("o.exr"),
                                "--rays", "2", "-q", "--no-passthrough"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_exr(path("o.exr")).channel_names(),
            std::set<std::string>(kOurChannels.begin(), kOurChannels.end()));
}

TEST_F(Cli, LayerPrefixMovesOurChannelsOnly) {
  // With or without the trailing dot, ours go under "ssgi."; the input's stay where they were.
  for (const std::string prefix : {"ssgi", "ssgi."}) {
    const CliResult r = run_ssgi({"run", testdata("sample/sample.0001.exr"), "-o", path("o.exr"),
                                  "--rays", "2", "-q", "--layer-prefix", prefix});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::set<std::string> expected = read_exr(testdata("sample/sample.0001.exr")).channel_names();
    for (const std::string& c : kOurChannels) expected.insert("ssgi." + c);
    EXPECT_EQ(read_exr(path("o.exr")).channel_names(), expected) << prefix;
  }
}

TEST_F(Cli, HalfDatatypeAppliesToOurChannelsOnlyAndClamps) {
  // The sample with an emission of 1e6 on every pixel: the composite is beyond half's range.
  ExrImage bright = read_exr(testdata("sample/sample.0001.exr"));
  std::fill(bright.planes.at("ViewLayer.Emit.R").begin(),
            bright.planes.at("ViewLayer.Emit.R").end(), 1e6f);
  write_exr(path("bright.0001.exr"), bright);
  const CliResult r = run_ssgi(
      {"run", path("bright.0001.exr"), "-o", path("o.exr"), "--rays", "2", "--datatype", "half"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // One warning for the frame, counting what was clamped, then the progress line, the summary.
  ASSERT_EQ(r.err_lines().size(), 3u) << r.err;
  EXPECT_EQ(r.err_lines()[0].rfind("ssgi: warning: " + path("o.exr") + ": ", 0), 0u) << r.err;
  EXPECT_NE(r.err_lines()[0].find(" values of ssgi's layers beyond the half-float range were "
                                  "clamped to +-65504"),
            std::string::npos)
      << r.err;
  const ExrImage out = read_exr(path("o.exr"));
  for (const std::string& c : out.spec.channelnames) {
    const bool ours = std::count(kOurChannels.begin(), kOurChannels.end(), c) > 0;
    EXPECT_EQ(out.format_of(c), ours ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT) << c;
  }
  // Clamped to the largest half on surfaces (background pixels show the beauty), never inf.
  const std::vector<float>& red = out.planes.at("R");
  EXPECT_EQ(*std::max_element(red.begin(), red.end()), 65504.0f);
  EXPECT_TRUE(std::all_of(red.begin(), red.end(), [](float v) { return std::isfinite(v); }));
}

TEST_F(Cli, DwaCompressionWritesAndWarnsOnce) {
  const CliResult r = run_ssgi({"run", testdata("sample/sample.1-2#.exr"), "-o", path("o.####.exr"),
                                "--rays", "2", "--compression", "dwaa:45"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // One warning for the run (not per frame), then the two progress lines and the summary.
  const std::vector<std::string> lines = r.err_lines();
  ASSERT_EQ(lines.size(), 4u) << r.err;
  EXPECT_EQ(lines[0],
            "ssgi: warning: DWA compression is lossy on channels named R, G, B "
            "(ssgi's outputs too)");
  const ExrImage out = read_exr(path("o.0002.exr"));
  EXPECT_EQ(out.spec.get_string_attribute("compression"), "dwaa");
  EXPECT_EQ(out.spec.get_float_attribute("openexr:dwaCompressionLevel"), 45.0f);
}

TEST_F(Cli, NoNanOrInfInOurChannelsOnAnyFixture) {
  // bad/nan.0001.exr has NaN and inf in depth, normals, albedo and direct light: sanitised on
  // reading, it must run like any other file.
  for (const Fixture& fixture : kSceneFixtures) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::vector<std::string> args = {
        "run", testdata(fixture.pattern), "-o", path("o.####.exr"), "--rays", "2", "--threads", "2",
        "-q"};
    args.insert(args.end(), fixture.flags.begin(), fixture.flags.end());
    const CliResult r = run_ssgi(args);
    ASSERT_EQ(r.exit_code, 0) << fixture.pattern << ": " << r.err;
    EXPECT_EQ(r.err, "") << fixture.pattern;
    ASSERT_FALSE(entries().empty());
    for (const std::string& name : entries()) {
      const ExrImage out = read_exr(path(name));
      for (const std::string& c : kOurChannels) {
        const std::vector<float>& plane = out.planes.at(c);
        const auto bad =
            std::find_if(plane.begin(), plane.end(), [](float v) { return !std::isfinite(v); });
        EXPECT_EQ(bad, plane.end())
            << fixture.pattern << " " << name << " " << c << " pixel " << (bad - plane.begin());
      }
    }
  }
}

TEST_F(Cli, RunningOnItsOwnOutputKeepsEveryChannelUniquelyNamed) {
  // ssgi's output fed back in twice: the first round's channels become input.*, the second's
  // input.input.*; no channel is lost or renamed by the EXR writer (channelNN).
  const std::string in = testdata("sample/sample.0001.exr");
  ASSERT_EQ(run_ssgi({"run", in, "-o", path("a.0001.exr"), "--rays", "2", "-q"}).exit_code, 0);
  ASSERT_EQ(run_ssgi({"run", path("a.0001.exr"), "-o", path("b.0001.exr"), "--rays", "2", "-q"})
                .exit_code,
            0);
  ASSERT_EQ(run_ssgi({"run", path("b.0001.exr"), "-o", path("c.0001.exr"), "--rays", "2", "-q"})
                .exit_code,
            0);
  const ExrImage a = read_exr(path("a.0001.exr"));
  const ExrImage c = read_exr(path("c.0001.exr"));
  EXPECT_EQ(c.planes.size(), a.planes.size() + 2 * kOurChannels.size());
  for (const auto& [name, plane] : c.planes) EXPECT_EQ(name.rfind("channel", 0), std::string::npos);
  EXPECT_EQ(c.planes.at("input.input.indirect.R"), a.planes.at("indirect.R"));
}

TEST_F(Cli, InputChannelsCollidingWithOursAreKeptAsInputDot) {
  // Two frames of the sample with an extra `R` and `indirect.R`, as a beauty or an earlier
  // ssgi run would leave.
  for (int f = 1; f <= 2; ++f) {
    const std::string frame = ".000" + std::to_string(f) + ".exr";
    ExrImage image = read_exr(testdata("sample/sample" + frame));
    const std::size_t pixels = image.planes.begin()->second.size();
    for (const char* c : {"R", "indirect.R"}) {
      image.spec.channelnames.push_back(c);
      image.planes[c].assign(pixels, 0.125f * f);
    }
    write_exr(path("in" + frame), image);
  }
  const CliResult r =
      run_ssgi({"run", path("in.####.exr"), "-o", path("out.####.exr"), "--rays", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // One warning for the whole run, then the two progress lines and the summary.
  const std::vector<std::string> lines = r.err_lines();
  ASSERT_EQ(lines.size(), 4u) << r.err;
  EXPECT_EQ(lines[0], "ssgi: warning: " + path("in.0001.exr") +
                          ": input channels that share a name with ssgi's are kept as "
                          "input.<name> (e.g. input.R)");
  for (int f = 1; f <= 2; ++f) {
    const ExrImage out = read_exr(path("out.000" + std::to_string(f) + ".exr"));
    const std::set<std::string> names = out.channel_names();
    EXPECT_EQ(names.count("input.R"), 1u);
    EXPECT_EQ(names.count("input.indirect.R"), 1u);
    // The input's values under the new names; ours under the plain ones.
    EXPECT_EQ(out.planes.at("input.R").front(), 0.125f * f);
    EXPECT_EQ(out.planes.at("input.indirect.R").back(), 0.125f * f);
    EXPECT_NE(out.planes.at("R"), out.planes.at("input.R"));
  }
}

// One part of an EXR in its own per-channel formats: the spec and the interleaved bytes.
struct NativePart {
  OIIO::ImageSpec spec;
  std::vector<unsigned char> bytes;
};

std::vector<NativePart> read_native_parts(const std::string& path) {
  std::vector<NativePart> parts;
  auto in = OIIO::ImageInput::open(path);
  EXPECT_TRUE(in) << path;
  if (!in) return parts;
  for (int s = 0; in->seek_subimage(s, 0); ++s) {
    NativePart part;
    part.spec = in->spec();
    part.bytes.resize(part.spec.image_bytes(true));
    EXPECT_TRUE(in->read_image(s, 0, 0, part.spec.nchannels, OIIO::TypeUnknown, part.bytes.data()))
        << path << " part " << s;
    parts.push_back(std::move(part));
  }
  return parts;
}

void write_native_parts(const std::string& path, const std::vector<NativePart>& parts) {
  std::vector<OIIO::ImageSpec> specs;
  for (const NativePart& p : parts) specs.push_back(p.spec);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, static_cast<int>(specs.size()), specs.data()))
      << path << ": " << (out ? out->geterror() : OIIO::geterror());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) {
      ASSERT_TRUE(out->open(path, specs[i], OIIO::ImageOutput::AppendSubimage))
          << path << " part " << i << ": " << out->geterror();
    }
    ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, parts[i].bytes.data())) << out->geterror();
  }
  ASSERT_TRUE(out->close());
}

// The bytes of channel `c` of every pixel of a native part, one after the other.
std::vector<unsigned char> channel_bytes(const NativePart& part, int c) {
  const std::size_t stride = part.spec.pixel_bytes(true);
  std::size_t offset = 0;
  for (int k = 0; k < c; ++k) offset += part.spec.channelformat(k).size();
  const std::size_t size = part.spec.channelformat(c).size();
  std::vector<unsigned char> out;
  for (std::size_t p = 0; p + stride <= part.bytes.size(); p += stride)
    out.insert(out.end(), part.bytes.begin() + p + offset, part.bytes.begin() + p + offset + size);
  return out;
}

// A part of `channels` float channels over `width` x `height` pixels at (x, y) of `frame`'s
// display window.
OIIO::ImageSpec part_of(const OIIO::ImageSpec& frame, int width, int height, int channels, int x,
                        int y) {
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
  spec.x = x;
  spec.y = y;
  spec.full_x = frame.full_x;
  spec.full_y = frame.full_y;
  spec.full_width = frame.full_width;
  spec.full_height = frame.full_height;
  return spec;
}

TEST_F(Cli, MultiPartInputComesBackInItsOwnTypesPartsAndAttributes) {
  // Part 0: the sample frame (float) plus a uint32 object ID above 2^24 (float would change
  // about half of them) and Cryptomatte's attributes; part 1: a Cryptomatte rank layer over a
  // smaller data window; part 2: half masks. All three come back as they were.
  const std::vector<NativePart> sample = read_native_parts(testdata("sample/sample.0001.exr"));
  ASSERT_EQ(sample.size(), 1u);
  const OIIO::ImageSpec& base = sample[0].spec;
  const std::size_t pixels = static_cast<std::size_t>(base.width) * base.height;
  std::vector<NativePart> parts(3);

  NativePart& beauty = parts[0];
  beauty.spec = base;
  beauty.spec.channelformats.assign(base.nchannels, OIIO::TypeDesc::FLOAT);
  beauty.spec.channelnames.push_back("objectId");
  beauty.spec.channelformats.push_back(OIIO::TypeDesc::UINT);
  beauty.spec.nchannels += 1;
  beauty.spec.attribute("oiio:subimagename", "rgba");
  beauty.spec.attribute("cryptomatte/3ae39a5/name", "CryptoObject");
  beauty.spec.attribute("cryptomatte/3ae39a5/hash", "MurmurHash3_32");
  beauty.spec.attribute("cryptomatte/3ae39a5/manifest", "{\"Cube\":\"3f800000\",\"Ball\":\"bf8\"}");
  const std::size_t base_bytes = base.pixel_bytes(true);
  for (std::size_t p = 0; p < pixels; ++p) {
    const unsigned char* src = sample[0].bytes.data() + p * base_bytes;
    beauty.bytes.insert(beauty.bytes.end(), src, src + base_bytes);
    const std::uint32_t id = (1u << 24) + 2654435761u * static_cast<std::uint32_t>(p);
    const auto* b = reinterpret_cast<const unsigned char*>(&id);
    beauty.bytes.insert(beauty.bytes.end(), b, b + 4);
  }

  NativePart& rank = parts[1];
  rank.spec = part_of(base, 40, 20, 4, 10, 5);
  rank.spec.channelnames = {"CryptoObject00.R", "CryptoObject00.G", "CryptoObject00.B",
                            "CryptoObject00.A"};
  rank.spec.attribute("oiio:subimagename", "crypto");
  rank.spec.attribute("cryptomatte/3ae39a5/conversion", "uint32_to_float32");
  for (int i = 0; i < 40 * 20 * 4; ++i) {
    const float v = 1e-3f * static_cast<float>(i) + 1e7f * static_cast<float>(i % 3);
    const auto* b = reinterpret_cast<const unsigned char*>(&v);
    rank.bytes.insert(rank.bytes.end(), b, b + 4);
  }

  NativePart& masks = parts[2];
  masks.spec = OIIO::ImageSpec(base.width, base.height, 2, OIIO::TypeDesc::HALF);
  masks.spec.x = base.x;
  masks.spec.y = base.y;
  masks.spec.full_x = base.full_x;
  masks.spec.full_y = base.full_y;
  masks.spec.full_width = base.full_width;
  masks.spec.full_height = base.full_height;
  masks.spec.channelnames = {"mask.R", "mask.G"};
  masks.spec.attribute("oiio:subimagename", "masks");
  for (std::size_t i = 0; i < 2 * pixels; ++i) {
    const std::uint16_t h = static_cast<std::uint16_t>(i * 37u);  // every bit pattern kind
    const auto* b = reinterpret_cast<const unsigned char*>(&h);
    masks.bytes.insert(masks.bytes.end(), b, b + 2);
  }
  write_native_parts(path("mp.0001.exr"), parts);

  const CliResult r =
      run_ssgi({"run", path("mp.0001.exr"), "-o", path("out.0001.exr"), "--rays", "2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<NativePart> got = read_native_parts(path("out.0001.exr"));
  ASSERT_EQ(got.size(), 3u);
  // Part 0: ours and every input channel, each in its own type with its own bytes (OpenEXR
  // keeps a part's channels sorted by name).
  const OIIO::ImageSpec& g0 = got[0].spec;
  ASSERT_EQ(g0.nchannels, static_cast<int>(kOurChannels.size()) + beauty.spec.nchannels);
  for (const std::string& c : kOurChannels) EXPECT_GE(g0.channelindex(c), 0) << c;
  for (int c = 0; c < beauty.spec.nchannels; ++c) {
    const std::string& name = beauty.spec.channelnames[c];
    const int oc = g0.channelindex(name);
    ASSERT_GE(oc, 0) << name;
    EXPECT_EQ(g0.channelformat(oc), beauty.spec.channelformat(c)) << name;
    EXPECT_EQ(channel_bytes(got[0], oc), channel_bytes(beauty, c)) << name;
  }
  EXPECT_EQ(g0.get_string_attribute("oiio:subimagename"), "rgba");
  for (const char* a : {"cryptomatte/3ae39a5/name", "cryptomatte/3ae39a5/hash",
                        "cryptomatte/3ae39a5/manifest", "BlenderMultiChannel"})
    EXPECT_EQ(g0.get_string_attribute(a), beauty.spec.get_string_attribute(a)) << a;
  EXPECT_FALSE(g0.get_string_attribute("ssgi:version").empty());
  // Parts 1 and 2: the same windows, channels, types, bytes and attributes.
  for (int k = 1; k <= 2; ++k) {
    const OIIO::ImageSpec& want = parts[k].spec;
    const OIIO::ImageSpec& have = got[k].spec;
    EXPECT_EQ(have.get_string_attribute("oiio:subimagename"),
              want.get_string_attribute("oiio:subimagename"));
    EXPECT_EQ(std::vector<int>({have.x, have.y, have.width, have.height}),
              std::vector<int>({want.x, want.y, want.width, want.height}));
    EXPECT_EQ(have.channelnames, want.channelnames);
    for (int c = 0; c < want.nchannels; ++c)
      EXPECT_EQ(have.channelformat(c), want.channelformat(c));
    EXPECT_EQ(got[k].bytes, parts[k].bytes) << "part " << k;
  }
  EXPECT_EQ(got[1].spec.get_string_attribute("cryptomatte/3ae39a5/conversion"),
            "uint32_to_float32");
}

// The input's channels are read from its file again when the frame is written, in strips of whole
// chunks of about 16 MB: frames of several strips come back byte for byte. A two-part frame, tiled
// (OIIO writes a multi-part file tiled or scanline throughout): its host part with tiles 48 rows
// tall, the other with 24 float channels over its own data window in tiles 80 rows tall (the
// output's strips are rows of the input's tiles). A scanline frame compressed with PIZ, 32
// scanlines a chunk, written with ZIP's 16 (its strips lcm(32, 16) rows).
TEST_F(Cli, PassthroughReadStripByStripKeepsEveryByteOfTilesAndTallChunks) {
  OIIO::ImageBuf sample(testdata("sample/sample.0001.exr"));
  OIIO::ImageSpec big = sample.spec();
  big.width = big.full_width = 1024;
  big.height = big.full_height = 680;
  OIIO::ImageBuf scaled(big);
  ASSERT_TRUE(OIIO::ImageBufAlgo::resample(scaled, sample, /*interpolate=*/false));
  NativePart host;
  host.spec = scaled.spec();
  host.spec.channelformats.clear();
  host.spec.set_format(OIIO::TypeDesc::FLOAT);
  host.bytes.resize(host.spec.image_bytes(true));
  ASSERT_TRUE(scaled.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, host.bytes.data()));
  ASSERT_GT(host.bytes.size(), std::size_t{48} << 20);  // several strips of 16 MB

  std::vector<NativePart> tiled(2, host);
  tiled[0].spec.tile_width = 32;
  tiled[0].spec.tile_height = 48;
  tiled[0].spec.attribute("oiio:subimagename", "host");
  tiled[0].spec.attribute("compression", "zip");
  NativePart& other = tiled[1];
  other.spec = part_of(big, 1000, 600, 24, 12, 40);
  other.spec.tile_width = 40;
  other.spec.tile_height = 80;
  other.spec.channelnames.clear();
  for (int c = 0; c < 24; ++c) other.spec.channelnames.push_back("aov" + std::to_string(c) + ".Y");
  other.spec.attribute("oiio:subimagename", "aovs");
  other.spec.attribute("compression", "piz");
  other.bytes.resize(other.spec.image_bytes(true));
  for (std::size_t i = 0; i < other.bytes.size() / 4; ++i) {
    const float v = static_cast<float>(i % 1000003) * 1e-3f;
    std::memcpy(other.bytes.data() + 4 * i, &v, 4);
  }
  write_native_parts(path("tiled.0001.exr"), tiled);
  NativePart piz = host;
  piz.spec.attribute("compression", "piz");
  write_native_parts(path("piz.0001.exr"), {piz});

  for (const char* name : {"tiled", "piz"}) {
    const std::string in = path(std::string(name) + ".0001.exr");
    const std::string out = path(std::string(name) + "_out.0001.exr");
    const CliResult r = run_ssgi({"run", in, "-o", out, "--rays", "2", "-q"});
    ASSERT_EQ(r.exit_code, 0) << name << r.err;
    const std::vector<NativePart> input = read_native_parts(in);
    const std::vector<NativePart> got = read_native_parts(out);
    ASSERT_EQ(got.size(), input.size()) << name;
    const OIIO::ImageSpec& made = got[0].spec;
    EXPECT_EQ(made.tile_height, input[0].spec.tile_height) << name;
    for (int c = 0; c < input[0].spec.nchannels; ++c) {
      const std::string& channel = input[0].spec.channelnames[c];
      const int oc = made.channelindex(channel);
      ASSERT_GE(oc, 0) << name << " " << channel;
      EXPECT_TRUE(channel_bytes(got[0], oc) == channel_bytes(input[0], c)) << name << channel;
    }
    for (std::size_t k = 1; k < input.size(); ++k) {
      const OIIO::ImageSpec& have = got[k].spec;
      EXPECT_EQ(std::vector<int>({have.x, have.y, have.width, have.height, have.tile_height}),
                std::vector<int>({12, 40, 1000, 600, 80}));
      EXPECT_EQ(have.channelnames, input[k].spec.channelnames);
      EXPECT_TRUE(got[k].bytes == input[k].bytes) << name << " part " << k;
    }
    // Not a copy of nothing: the light is there.
    double light = 0;
    const std::vector<unsigned char> gi = channel_bytes(got[0], made.channelindex("gi.R"));
    for (std::size_t i = 0; i + 4 <= gi.size(); i += 4) {
      float v;
      std::memcpy(&v, gi.data() + i, 4);
      light += v;
    }
    EXPECT_GT(light, 0) << name;
  }
}

TEST_F(Cli, PassesSpreadOverPartsWithTheirOwnDataWindowsRun) {
  // As Nuke writes them: geometry in a part over the whole frame, the light passes in a part
  // with its own, smaller data window. The run reads the light part's pixels where they are
  // (0 outside, as OpenEXR reads outside a data window), and passes both parts through as they
  // were. Against the same passes in one part, cropped the same way (zeros outside): the same
  // bits.
  const OIIO::ImageBuf source(testdata("sample/sample.0001.exr"));
  const std::vector<std::string> geo = {"ViewLayer.Depth.Z", "ViewLayer.Normal.X",
                                        "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"};
  const std::vector<std::string> light = {"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G",
                                          "ViewLayer.DiffCol.B", "ViewLayer.DiffDir.R",
                                          "ViewLayer.DiffDir.G", "ViewLayer.DiffDir.B"};
  auto channels = [&](const std::vector<std::string>& names) {
    std::vector<int> order;
    for (const std::string& n : names) order.push_back(source.spec().channelindex(n));
    return OIIO::ImageBufAlgo::channels(source, static_cast<int>(order.size()), order, {}, names);
  };
  OIIO::ImageBuf geo_part = channels(geo);
  const OIIO::ROI crop(10, 81, 8, 51, 0, 1, 0, static_cast<int>(light.size()));
  OIIO::ImageBuf light_part = OIIO::ImageBufAlgo::cut(channels(light), crop);
  light_part.set_origin(10, 8);  // cut moves the window to 0,0
  std::vector<NativePart> parts;
  for (const OIIO::ImageBuf* part : {&geo_part, &light_part}) {
    NativePart p;
    p.spec = part->spec();
    p.spec.set_format(OIIO::TypeDesc::FLOAT);
    p.spec.channelformats.clear();
    for (const OIIO::ParamValue& a : source.spec().extra_attribs)
      if (a.name().string().rfind("world", 0) == 0 || a.name() == "BlenderMultiChannel")
        p.spec.attribute(a.name(), a.type(), a.data());
    p.spec.attribute("oiio:subimagename", part == &geo_part ? "geo" : "light");
    p.spec.full_x = p.spec.full_y = p.spec.full_z = 0;  // one display window for all parts
    p.spec.full_width = 96, p.spec.full_height = 64, p.spec.full_depth = 1;
    p.spec.tile_width = p.spec.tile_height = p.spec.tile_depth = 0;  // scanline parts
    p.bytes.resize(p.spec.image_bytes());
    ASSERT_TRUE(part->get_pixels(part->roi(), OIIO::TypeDesc::FLOAT, p.bytes.data()));
    parts.push_back(std::move(p));
  }
  write_native_parts(path("parts.0001.exr"), parts);
  // The same passes in one part over the whole frame, zero outside the crop.
  ExrImage one = read_exr(testdata("sample/sample.0001.exr"));
  one.spec.channelnames = geo;  // the same passes, nothing else
  one.spec.channelnames.insert(one.spec.channelnames.end(), light.begin(), light.end());
  for (const std::string& n : light)
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 96; ++x)
        if (!(x >= 10 && x < 81 && y >= 8 && y < 51)) one.planes.at(n)[y * 96 + x] = 0.0f;
  write_exr(path("one.0001.exr"), one);
  for (const char* name : {"parts", "one"}) {
    const CliResult r = run_ssgi({"run", path(std::string(name) + ".0001.exr"), "-o",
                                  path(std::string("o_") + name + ".0001.exr"), "-q"});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
  }
  const ExrImage a = read_exr(path("o_parts.0001.exr"));
  const ExrImage b = read_exr(path("o_one.0001.exr"));
  for (const std::string& c : kOurChannels) EXPECT_EQ(a.planes.at(c), b.planes.at(c)) << c;
  const std::vector<float>& ind = a.planes.at("indirect.G");
  EXPECT_GT(*std::max_element(ind.begin(), ind.end()), 0.0f);
  // The light part comes through with its own window.
  auto in = OIIO::ImageInput::open(path("o_parts.0001.exr"));
  ASSERT_TRUE(in && in->seek_subimage(1, 0));
  EXPECT_EQ(in->spec().x, 10);
  EXPECT_EQ(in->spec().width, 71);
  EXPECT_EQ(in->spec().nchannels, 6);
}

TEST_F(Cli, FrameWithoutSurfacesWarnsAndSaysWhy) {
  // Positive depth read as negative: every pixel is background. The position pass says which
  // kind the depth is, and the frame gets one warning naming it and the likely cause.
  const CliResult r = run_ssgi({"run", testdata("sample/sample.0001.exr"), "-o", path("o.exr"),
                                "--rays", "2", "--temporal", "none", "--depth-kind", "negative"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = r.err_lines();
  ASSERT_EQ(lines.size(), 4u) << r.err;  // two warnings, the progress line, the summary
  EXPECT_EQ(lines[0], "ssgi: warning: " + testdata("sample/sample.0001.exr") +
                          ": ViewLayer.Depth.Z holds planar depth by the position pass " +
                          "ViewLayer.Position (5976 of 5976 pixels), not negative: give " +
                          "--depth-kind planar");
  EXPECT_EQ(lines[1], "ssgi: warning: " + testdata("sample/sample.0001.exr") + ": 0 of 6144 " +
                          "pixels have a surface, the rest get no GI: its depths are positive " +
                          "but --depth-kind is negative");
  // The right kind: no warning.
  const CliResult ok = run_ssgi({"run", testdata("sample/sample.0001.exr"), "-o", path("p.exr"),
                                 "--rays", "2", "--temporal", "none", "--depth-kind", "planar"});
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(ok.err_lines().size(), 2u) << ok.err;  // the progress line and the summary
}

TEST_F(Cli, OneChannelLayerIsFoundByItsName) {
  // The sample with its depth as the single channel of layer `zdist` (component Y).
  ExrImage image = read_exr(testdata("sample/sample.0001.exr"));
  for (std::string& name : image.spec.channelnames)
    if (name == "ViewLayer.Depth.Z") name = "zdist.Y";
  image.planes["zdist.Y"] = image.planes.at("ViewLayer.Depth.Z");
  write_exr(path("z.0001.exr"), image);
  const CliResult r = run_ssgi({"run", path("z.0001.exr"), "-o", path("z_out.exr"), "--rays", "2",
                                "-q", "--channel", "depth=zdist"});
  // The plain frame alone too (its neighbours on disk would join its temporal window).
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CliResult plain = run_ssgi({"run", testdata("sample/sample.0001.exr"), "-o",
                                    path("plain.exr"), "--rays", "2", "-q", "--temporal", "none"});
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  // The same depth, so the same light as the plain file.
  const std::vector<float> got = read_exr(path("z_out.exr")).planes.at("indirect.R");
  EXPECT_EQ(got, read_exr(path("plain.exr")).planes.at("indirect.R"));
  EXPECT_GT(*std::max_element(got.begin(), got.end()), 0.0f);
}

TEST_F(Cli, StatsRecordEachFramesTimingsAndTheSettings) {
  const CliResult r = run_ssgi({"run", testdata("sample/sample.1-3#.exr"), "-o", path("o.####.exr"),
                                "-q", "--preset", "draft", "--stats", path("stats.json")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream file(path("stats.json"));
  const nlohmann::json stats = nlohmann::json::parse(file, nullptr, false);
  ASSERT_FALSE(stats.is_discarded());
  EXPECT_EQ(stats["settings"]["preset"], "draft");
  EXPECT_EQ(stats["settings"]["tracer"], "slices");
  ASSERT_EQ(stats["frames"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const nlohmann::json& f = stats["frames"][i];
    EXPECT_EQ(f["frame"], i + 1);
    EXPECT_EQ(f["ok"], true);
    // Every frame reads, computes and writes something: each time is positive.
    for (const char* key : {"read_ms", "gi_ms", "write_ms"}) {
      ASSERT_TRUE(f[key].is_number()) << key;
      EXPECT_GT(f[key].get<double>(), 0.0) << key;
    }
  }
  EXPECT_GT(stats["median"]["gi_ms"].get<double>(), 0.0);
  // No temporary file left beside it; info refuses the option.
  EXPECT_EQ(entries(),
            (std::set<std::string>{"o.0001.exr", "o.0002.exr", "o.0003.exr", "stats.json"}));
  expect_usage_error(
      run_ssgi({"info", testdata("sample/sample.0001.exr"), "--stats", "s.json"}), "info",
      "'--stats' is not an option of ssgi info (it is of ssgi run or ssgi reference)");
}

}  // namespace
}  // namespace cli_test
