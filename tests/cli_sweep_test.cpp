// `ssgi sweep`: each preset timed and measured against a truth layer, the CSV and the plot, and
// the options it refuses.
#include <fcntl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

// The rows of a CSV file without quoted cells, each split at its commas.
std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    rows.push_back(cells);
  }
  return rows;
}

TEST_F(Cli, SweepTimesAndMeasuresEachPresetAndDrawsThePlot) {
  // Two frames of the sample fixture, two presets, a 32-ray reference: small, so that the test
  // is quick. The fixtures have no path-traced truth; DiffDir, a layer every frame has, stands
  // in for --truth.
  const std::string in = testdata("sample/sample.1-2#.exr");
  fs::create_directories(path("tmp"));
  ::setenv("TMPDIR", path("tmp").c_str(), 1);  // where the sweep's scratch directory goes
  const CliResult r = run_ssgi({"sweep", in, "--presets", "draft,final", "--reference-spp", "32",
                                "--truth", "DiffDir", "--repeat", "3", "-o", path("t.csv"),
                                "--json", path("t.json"), "--plot", path("t.png")});
  ::unsetenv("TMPDIR");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  // The scratch frames are gone, and nothing but the three outputs is left.
  EXPECT_EQ(entries(), (std::set<std::string>{"t.csv", "t.json", "t.png", "tmp"}));
  EXPECT_TRUE(fs::is_empty(path("tmp")));
  EXPECT_NE(r.err.find("ssgi: round 1/3, run 2/2 final: "), std::string::npos) << r.err;

  const auto csv = read_csv(path("t.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0],
            (std::vector<std::string>{"name", "settings", "ms_per_frame", "relrmse_ref", "psnr_ref",
                                      "ssim_ref", "relrmse_truth", "psnr_truth", "ssim_truth"}));
  ASSERT_EQ(csv[1].size(), 9u);
  ASSERT_EQ(csv[2].size(), 9u);
  EXPECT_EQ(csv[1][0], "draft");
  EXPECT_EQ(csv[1][1], "slices=1 max-steps=16 trace-width=240 bounces=4");
  EXPECT_EQ(csv[2][0], "final");
  EXPECT_EQ(csv[2][1], "slices=4 max-steps=28 trace-width=480 bounces=8");
  auto value = [&](int row, int column) { return std::stod(csv[row][column]); };
  for (int row : {1, 2}) {
    EXPECT_GT(value(row, 2), 0.0);
    // A run that traced nothing (indirect 0) would have relRMSE of at least 1 against both.
    EXPECT_GT(value(row, 3), 0.0);
    EXPECT_LT(value(row, 3), 0.3);  // measured 0.116 (draft) and 0.089 (final)
    EXPECT_GT(value(row, 4), 15.0);
    EXPECT_LT(value(row, 4), 60.0);
    EXPECT_GT(value(row, 5), 0.0);
    EXPECT_LE(value(row, 5), 1.0);
    EXPECT_GT(value(row, 6), 0.0);
    EXPECT_GT(value(row, 7), 0.0);
    EXPECT_GT(value(row, 8), 0.0);
    EXPECT_LE(value(row, 8), 1.0);
  }
  // final traces 4 slices x 28 samples a side with 8 bounces, draft 1 x 16 with 4: several
  // times the work, and closer to the reference.
  EXPECT_LT(value(1, 2), value(2, 2));
  EXPECT_LT(value(2, 3), value(1, 3));

  // The truth columns are ssgi compare's numbers for the same run against the input's layer.
  ASSERT_EQ(
      run_ssgi({"run", in, "-o", path("o.####.exr"), "-q", "--preset", "draft", "--no-passthrough"})
          .exit_code,
      0);
  const CliResult compared =
      run_ssgi({"compare", "--metric", "relrmse", "--channels", "indirect=ViewLayer.DiffDir",
                "--json", path("o.1-2#.exr"), in});
  const nlohmann::json summary = nlohmann::json::parse(compared.out, nullptr, false);
  ASSERT_FALSE(summary.is_discarded()) << compared.out << compared.err;
  EXPECT_NEAR(value(1, 6), summary["summary"]["overall"]["relrmse"]["mean"].get<double>(), 5e-5);

  std::ifstream json_file(path("t.json"));
  const nlohmann::json json = nlohmann::json::parse(json_file, nullptr, false);
  ASSERT_FALSE(json.is_discarded());
  EXPECT_EQ(json["frames"], "1-2");
  EXPECT_EQ(json["truth"], "ViewLayer.DiffDir");
  EXPECT_EQ(json["reference"]["spp"], 32);
  ASSERT_EQ(json["rows"].size(), 2u);
  EXPECT_EQ(json["rows"][0]["name"], "draft");
  EXPECT_EQ(json["rows"][1]["all_settings"]["slices"], "4");
  EXPECT_EQ(json["rows"][1]["all_settings"]["temporal"], "window:2");
  for (int row : {0, 1}) {
    const nlohmann::json& j = json["rows"][row];
    ASSERT_EQ(j["gi_ms"].size(), 6u);  // 2 frames x 3 rounds
    for (const auto& ms : j["gi_ms"]) EXPECT_GT(ms.get<double>(), 0.0);
    // Time per frame: the mean over the frames of the fastest round.
    ASSERT_EQ(j["round_ms"].size(), 3u);
    double fastest = 1e30;
    for (int round = 0; round < 3; ++round) {
      const double round_mean =
          0.5 * (j["gi_ms"][2 * round].get<double>() + j["gi_ms"][2 * round + 1].get<double>());
      EXPECT_NEAR(j["round_ms"][round].get<double>(), round_mean, 1e-9);
      fastest = std::min(fastest, round_mean);
    }
    EXPECT_DOUBLE_EQ(j["ms_per_frame"].get<double>(), fastest);
    EXPECT_NEAR(j["ms_per_frame"].get<double>(), value(row + 1, 2), 0.05);
    EXPECT_NEAR(j["relrmse_ref"].get<double>(), value(row + 1, 3), 5e-5);
    // On the front unless the other row is as fast and as close (to the truth, which the plot
    // draws when given), and better in one.
    const int other = 3 - (row + 1);
    const bool dominated =
        value(other, 2) <= value(row + 1, 2) && value(other, 6) <= value(row + 1, 6) &&
        (value(other, 2) < value(row + 1, 2) || value(other, 6) < value(row + 1, 6));
    EXPECT_EQ(j["pareto"], !dominated);
  }

  // The plot: 1200x800 RGB, white paper, dark ink, and the front's blue markers.
  auto png = OIIO::ImageInput::open(path("t.png"));
  ASSERT_TRUE(png) << OIIO::geterror();
  const OIIO::ImageSpec spec = png->spec();
  EXPECT_EQ(spec.width, 1200);
  EXPECT_EQ(spec.height, 800);
  ASSERT_EQ(spec.nchannels, 3);
  std::vector<unsigned char> pixels(static_cast<std::size_t>(spec.width) * spec.height * 3);
  ASSERT_TRUE(png->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
  std::size_t white = 0, ink = 0, blue = 0;
  for (std::size_t i = 0; i < pixels.size(); i += 3) {
    const int red = pixels[i], green = pixels[i + 1], b = pixels[i + 2];
    white += red == 255 && green == 255 && b == 255;
    ink += red < 60 && green < 60 && b < 60;
    blue += std::abs(red - 31) < 4 && std::abs(green - 89) < 4 && std::abs(b - 191) < 4;
  }
  EXPECT_GT(white, pixels.size() / 3 / 2);
  EXPECT_GT(ink, 2000u);  // frame, ticks and text
  EXPECT_GT(blue, 200u);  // two filled markers of radius 6 and the front's line
}

TEST_F(Cli, SweepRefusesBadOptionsAndUnknownTruthLayers) {
  const std::string in = testdata("sample/sample.1-2#.exr");
  const std::string csv = path("t.csv");
  expect_usage_error(run_ssgi({"sweep", in, "-o", csv, "--presets", "draft,fast"}), "sweep",
                     "--presets: unknown preset 'fast' (draft, default, final)");
  expect_usage_error(run_ssgi({"sweep", in}), "sweep", "no output given (-o FILE.csv)");
  expect_usage_error(run_ssgi({"sweep", in, "-o", csv, "--repeat", "0"}), "sweep",
                     "--repeat: '0' is not an integer in [1, 100]");
  expect_usage_error(run_ssgi({"sweep", in, "-o", csv, "--presets", ""}), "sweep",
                     "nothing to run: --presets is empty and --grid is not given");
  expect_usage_error(run_ssgi({"sweep", in, "-o", csv, "--spp", "8"}), "sweep",
                     "'--spp' is not an option of ssgi sweep (it is of ssgi reference)");
  expect_usage_error(run_ssgi({"run", in, "-o", path("o.####.exr"), "--grid"}), "run",
                     "'--grid' is not an option of ssgi run (it is of ssgi sweep)");
  // A truth layer the input lacks: input data unusable, before anything is traced.
  const CliResult r = run_ssgi({"sweep", in, "-o", csv, "--truth", "DiffInd"});
  EXPECT_EQ(r.exit_code, 3);
  expect_one_error(r, testdata("sample/sample.0001.exr"), "has no R,G,B layer 'DiffInd'");
  EXPECT_TRUE(entries().empty());
  const CliResult help = run_ssgi({"sweep", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_EQ(help.out.rfind("usage: ssgi sweep INPUT -o TABLE.csv", 0), 0u);
  EXPECT_NE(help.out.find("--reference-spp N"), std::string::npos);
  EXPECT_EQ(help.out.find("--preset P"), std::string::npos);
}

}  // namespace
}  // namespace cli_test
