// Guides end to end (--guide): the still room's frames with a guide made from them (its indirect
// light known), at the shot's resolution and at half of it, what `info` says, and the guides a
// run must refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

constexpr int kFrames = 10;
const char* const kIndirect[] = {"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G",
                                 "ViewLayer.DiffInd.B"};

std::string frame_name(const std::string& stem, int f) {
  char name[64];
  std::snprintf(name, sizeof name, "%s.%04d.exr", stem.c_str(), f);
  return name;
}

// The guide's light at a pixel: a ramp across the frame, its own per channel.
float guide_light(int c, int x, int y) { return 0.05f + 0.1f * c + 0.004f * x + 0.002f * y; }

class CliGuide : public Cli {
 protected:
  // Frames 1..kFrames of the still room as guide.####.exr in the test directory with a
  // DiffInd pass of `light` (channel, x, y on the guide's lattice), at 1 / `fraction` of the
  // shot's resolution (each guide pixel the shot pixel at its centre); `edit` changes a frame
  // before it is written.
  void write_guide(int fraction, const std::function<float(int, int, int)>& light,
                   const std::function<void(int, ExrImage*)>& edit = nullptr) const {
    for (int f = 1; f <= kFrames; ++f) {
      const ExrImage shot = read_exr(testdata("static/" + frame_name("static", f)));
      ExrImage g;
      g.spec = shot.spec;
      const int w = shot.spec.width / fraction, h = shot.spec.height / fraction;
      g.spec.width = g.spec.full_width = w;
      g.spec.height = g.spec.full_height = h;
      g.spec.channelnames.clear();
      for (const auto& [name, plane] : shot.planes) {
        std::vector<float> small(static_cast<std::size_t>(w) * h);
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x)
            small[static_cast<std::size_t>(y) * w + x] =
                plane[static_cast<std::size_t>(y * fraction + fraction / 2) * shot.spec.width +
                      x * fraction + fraction / 2];
        g.planes[name] = std::move(small);
        g.spec.channelnames.push_back(name);
      }
      // No diffuse light where there is no diffuse albedo (the room's lamp), as renderers write.
      const auto no_albedo = [&](std::size_t p) {
        return g.planes.at("ViewLayer.DiffCol.R")[p] == 0 &&
               g.planes.at("ViewLayer.DiffCol.G")[p] == 0 &&
               g.planes.at("ViewLayer.DiffCol.B")[p] == 0;
      };
      for (int c = 0; c < 3; ++c) {
        std::vector<float> plane(static_cast<std::size_t>(w) * h);
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) {
            const std::size_t p = static_cast<std::size_t>(y) * w + x;
            plane[p] = no_albedo(p) ? 0.0f : light(c, x, y);
          }
        g.planes[kIndirect[c]] = std::move(plane);
        g.spec.channelnames.push_back(kIndirect[c]);
      }
      if (edit) edit(f, &g);
      write_exr(path(frame_name("guide", f)), g);
    }
  }

  CliResult run(const std::vector<std::string>& extra) const {
    std::vector<std::string> args = {"run",
                                     testdata("static/static.####.exr"),
                                     "-o",
                                     path("out.####.exr"),
                                     "-q",
                                     "--guide",
                                     path("guide.####.exr")};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_ssgi(args);
  }
};

// The largest difference of an output's indirect light to `expected` (channel, x, y) over the
// shot's surface pixels (depth below 1e9) with an albedo (those without reflect no diffuse light,
// as in the renderers' passes), relative to the expected value.
double largest_difference(const ExrImage& out,
                          const std::function<float(int, int, int)>& expected) {
  const std::vector<float>& depth = out.planes.at("ViewLayer.Depth.Z");
  const char* const names[] = {"indirect.R", "indirect.G", "indirect.B"};
  double worst = 0;
  int surfaces = 0;
  for (int y = 0; y < out.spec.height; ++y)
    for (int x = 0; x < out.spec.width; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * out.spec.width + x;
      if (!(depth[p] < 1e9f)) continue;
      if (out.planes.at("ViewLayer.DiffCol.R")[p] == 0 &&
          out.planes.at("ViewLayer.DiffCol.G")[p] == 0 &&
          out.planes.at("ViewLayer.DiffCol.B")[p] == 0)
        continue;
      ++surfaces;
      for (int c = 0; c < 3; ++c) {
        const double want = expected(c, x, y);
        worst = std::max(worst, std::fabs(out.planes.at(names[c])[p] - want) / want);
      }
    }
  EXPECT_GT(surfaces, 100);
  return worst;
}

TEST_F(CliGuide, AGuideWithoutNoiseGivesItsOwnLightThroughTheWindow) {
  write_guide(1, guide_light);
  for (const char* temporal : {"window", "none"}) {
    const CliResult r = run({"--frames", "4-6", "--temporal", temporal});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (int f = 4; f <= 6; ++f)
      EXPECT_LT(largest_difference(read_exr(path(frame_name("out", f))), guide_light), 1e-4)
          << temporal << " frame " << f;
  }
  // ssgi alone is far from it: the guide brought its light.
  const CliResult alone = run_ssgi({"run", testdata("static/static.####.exr"), "-o",
                                    path("alone.####.exr"), "-q", "--frames", "5"});
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  EXPECT_GT(largest_difference(read_exr(path(frame_name("alone", 5))), guide_light), 0.3);
}

TEST_F(CliGuide, AGuideAtHalfTheResolutionGivesItsLight) {
  const auto flat = [](int c, int, int) { return 0.1f + 0.05f * c; };
  write_guide(2, flat);
  const CliResult r =
      run_ssgi({"run", testdata("static/static.####.exr"), "-o", path("out.####.exr"), "--guide",
                path("guide.####.exr"), "--frames", "5", "-v"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1/2 of it"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frame 5: guide: gives the light of "), std::string::npos) << r.err;
  EXPECT_LT(largest_difference(read_exr(path(frame_name("out", 5))), flat), 1e-4);
}

TEST_F(CliGuide, StatsSayWhatTheGuideBrought) {
  // A ramp without noise, unlike ssgi's light: its residual brings a share of the light, and
  // its detail is kept whole.
  write_guide(1, guide_light);
  const CliResult r = run({"--frames", "5", "--stats", path("stats.json")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(path("stats.json"));
  const nlohmann::json stats = nlohmann::json::parse(in);
  const nlohmann::json& guide = stats.at("frames").at(0).at("guide");
  EXPECT_NEAR(guide.at("known_share").get<double>(), 1.0, 0.05);
  EXPECT_EQ(guide.at("detail_kept").get<double>(), 1.0);  // a guide without noise
  const double share = guide.at("residual_share").get<double>();
  EXPECT_NE(share, 0.0);
  EXPECT_GT(share, -1.0);
  EXPECT_LT(share, 1.0);
  // Without a guide there is no such object.
  const CliResult alone =
      run_ssgi({"run", testdata("static/static.####.exr"), "-o", path("alone.####.exr"), "-q",
                "--frames", "5", "--stats", path("alone.json")});
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  std::ifstream alone_in(path("alone.json"));
  EXPECT_FALSE(nlohmann::json::parse(alone_in).at("frames").at(0).contains("guide"));
}

TEST_F(CliGuide, TheSweepRunsEachPresetWithAndWithoutTheGuide) {
  // The guide's files as the shot too, so that their DiffInd is the truth the rows are measured
  // against: with the guide a run gives it back, without it ssgi alone is far from the ramp.
  write_guide(1, guide_light);
  const CliResult r = run_ssgi({"sweep", path("guide.####.exr"), "--frames", "4-6", "--presets",
                                "draft", "--reference-spp", "8", "--truth", "DiffInd", "--guide",
                                path("guide.####.exr"), "-o", path("t.csv")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(path("t.csv"));
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1][0], "draft");
  EXPECT_EQ(rows[2][0], "draft+guide");
  EXPECT_GT(std::stod(rows[1][6]), 0.1) << "ssgi alone against the ramp";
  EXPECT_LT(std::stod(rows[2][6]), 1e-3) << "with the guide that is the truth";
  EXPECT_GT(std::stod(rows[2][2]), 0.0);
}

TEST_F(CliGuide, InfoNamesTheGuideInThePlan) {
  write_guide(1, guide_light);
  const CliResult r =
      run_ssgi({"info", testdata("static/static.####.exr"), "--guide", path("guide.####.exr")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("guide: " + path("guide.####.exr") + " (the shot's resolution)"),
            std::string::npos)
      << r.out;
}

TEST_F(CliGuide, AGuideThatDoesNotCoverTheRunIsRefusedBeforeAnythingIsWritten) {
  write_guide(1, guide_light);
  // Frame 7 is a neighbour of frame 5 in the window.
  fs::remove(path(frame_name("guide", 7)));
  const CliResult r = run({"--frames", "5"});
  EXPECT_EQ(r.exit_code, 4);
  expect_one_error(r, path(frame_name("guide", 7)), "of the guide is missing");
  EXPECT_FALSE(fs::exists(path(frame_name("out", 5))));
}

TEST_F(CliGuide, GuidesThatAreNotTheShotsAreRefused) {
  // Without the indirect light.
  write_guide(1, guide_light, [](int, ExrImage* g) {
    for (const char* name : kIndirect) {
      g->planes.erase(name);
      auto& names = g->spec.channelnames;
      names.erase(std::find(names.begin(), names.end(), name));
    }
  });
  CliResult r = run({"--frames", "5"});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, path(frame_name("guide", 5)), "has no indirect channels");
  // At a resolution that is not a whole fraction of the shot's (48 x 32 / 48 x 24).
  write_guide(1, guide_light, [](int, ExrImage* g) {
    g->spec.height = g->spec.full_height = 24;
    for (auto& [name, plane] : g->planes) plane.resize(48 * 24);
  });
  r = run({"--frames", "5"});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, path(frame_name("guide", 5)), "is not the shot's 48 x 32 divided by");
  // Another camera: the room seen mirrored.
  write_guide(1, guide_light, [](int, ExrImage* g) {
    std::vector<float>& z = g->planes.at("ViewLayer.Depth.Z");
    for (int y = 0; y < g->spec.height; ++y)
      std::reverse(z.begin() + y * g->spec.width, z.begin() + (y + 1) * g->spec.width);
    std::reverse(z.begin(), z.end());
  });
  r = run({"--frames", "5", "--temporal", "none"});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, path(frame_name("guide", 5)), "not a render of the shot's camera");
  EXPECT_FALSE(fs::exists(path(frame_name("out", 5))));
}

TEST_F(CliGuide, AGuideWithNaNFailsItsFrameNamingTheGuide) {
  write_guide(1, guide_light, [](int f, ExrImage* g) {
    if (f == 5) g->planes.at(kIndirect[1])[100] = std::numeric_limits<float>::quiet_NaN();
  });
  const CliResult r = run({"--frames", "5", "--temporal", "none"});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, path(frame_name("guide", 5)), "1 NaN or infinite values in its indirect");
  EXPECT_FALSE(fs::exists(path(frame_name("out", 5))));
}

TEST_F(CliGuide, TheRunningAverageTakesNoGuide) {
  write_guide(1, guide_light);
  expect_usage_error(run({"--frames", "5", "--temporal", "ema"}), "run",
                     "--guide: the guide is filtered over the symmetric temporal window or over "
                     "each frame alone: use --temporal window or none with it, not ema");
}

}  // namespace
}  // namespace cli_test
