// Tests of `ssgi compare`: metrics against values worked out by hand on tiny images, idiff's
// threshold rules, channel selection by name, and the CLI's exit codes on small EXRs.
#include "ssgi/compare.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ssgi/error.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInfF = std::numeric_limits<float>::infinity();
// Inputs are exact in float and sums are in double: only the last bits of sqrt/log10 differ.
constexpr double kTight = 1e-12;

Image image_from(int w, int h, const std::vector<std::vector<float>>& planes) {
  Image img(w, h, static_cast<int>(planes.size()));
  for (int c = 0; c < img.channels(); ++c)
    std::copy(planes[c].begin(), planes[c].end(), img.plane(c));
  return img;
}

double metric(const LayerStats& s, Metric m) {
  EXPECT_TRUE(s.metric(m).has_value()) << metric_name(m);
  return s.metric(m).value_or(std::nan(""));
}

CompareOptions options_without_ssim() {
  CompareOptions options;
  options.compute_ssim = false;
  return options;
}

// b = {1, 2, 3, 4}, a = b + {0.5, -0.5, 0, 1}: sum of squares 1.5 over 4 samples.
TEST(CompareMetrics, HandComputedTwoByTwo) {
  const Image b = image_from(2, 2, {{1, 2, 3, 4}});
  const Image a = image_from(2, 2, {{1.5f, 1.5f, 3, 5}});
  const CompareResult r = compare_images(a, b, {{"Y", {0}, false}}, options_without_ssim());
  ASSERT_EQ(r.layers.size(), 1u);
  const LayerStats& s = r.layers[0];
  EXPECT_EQ(s.samples, 4u);
  EXPECT_NEAR(metric(s, Metric::kRmse), 0.6123724356957945, kTight);     // sqrt(1.5 / 4)
  EXPECT_NEAR(metric(s, Metric::kRelRmse), 0.2449489742783178, kTight);  // rmse / 2.5
  // (0.25/1.01 + 0.25/4.01 + 0/9.01 + 1/16.01) / 4
  EXPECT_NEAR(metric(s, Metric::kRelMse), 0.09308246350623339, kTight);
  EXPECT_NEAR(metric(s, Metric::kPsnr), 16.300887149282058, kTight);  // 10 log10(4^2 / 0.375)
  EXPECT_FALSE(s.metric(Metric::kSsim).has_value());
  EXPECT_DOUBLE_EQ(s.reference_peak, 4.0);
  EXPECT_DOUBLE_EQ(s.reference_mean, 2.5);
  EXPECT_DOUBLE_EQ(s.max_error, 1.0);
}

// A second layer b = {2, 2, 2, 2}, a = {2, 2, 2, 3} adds 1.0 to the squares over 4 samples.
TEST(CompareMetrics, OverallPoolsSamplesOfAllLayers) {
  const Image b = image_from(2, 2, {{1, 2, 3, 4}, {2, 2, 2, 2}});
  const Image a = image_from(2, 2, {{1.5f, 1.5f, 3, 5}, {2, 2, 2, 3}});
  const CompareResult r =
      compare_images(a, b, {{"one", {0}, false}, {"two", {1}, false}}, options_without_ssim());
  ASSERT_EQ(r.layers.size(), 2u);
  EXPECT_NEAR(metric(r.layers[1], Metric::kRmse), 0.5, kTight);
  EXPECT_EQ(r.overall.name, "all");
  EXPECT_EQ(r.overall.samples, 8u);
  EXPECT_NEAR(metric(r.overall, Metric::kRmse), 0.5590169943749475, kTight);      // sqrt(2.5 / 8)
  EXPECT_NEAR(metric(r.overall, Metric::kRelRmse), 0.24845199749997665, kTight);  // / 2.25
  EXPECT_NEAR(metric(r.overall, Metric::kPsnr), 17.09269960975831, kTight);       // peak 4

  // Per-pixel differences (largest over both planes) are {0.5, 0.5, 0, 1}.
  EXPECT_EQ(r.pixels.pixels, 4u);
  EXPECT_EQ(r.pixels.warn_pixels, 3u);  // default thresholds 1e-6
  EXPECT_EQ(r.pixels.fail_pixels, 3u);
  EXPECT_DOUBLE_EQ(r.pixels.max_error, 1.0);
  EXPECT_EQ(r.pixels.max_x, 1);
  EXPECT_EQ(r.pixels.max_y, 1);
  EXPECT_EQ(r.pixels.max_plane, 0);  // the first plane reaching the maximum
  EXPECT_EQ(r.status, CompareStatus::kFail);
}

TEST(CompareMetrics, IdenticalImagesHaveZeroErrorInfinitePsnrAndSsimOne) {
  Image b(7, 5, 3);
  for (std::size_t i = 0; i < b.data().size(); ++i) b.data()[i] = 0.1f + (i * 37 % 11) * 0.2f;
  const CompareResult r = compare_images(b, b, {{"rgb", {0, 1, 2}, true}}, CompareOptions{});
  const LayerStats& s = r.layers[0];
  EXPECT_EQ(metric(s, Metric::kRmse), 0.0);
  EXPECT_EQ(metric(s, Metric::kRelMse), 0.0);
  EXPECT_TRUE(std::isinf(metric(s, Metric::kPsnr)));
  EXPECT_NEAR(metric(s, Metric::kSsim), 1.0, 1e-12);
  EXPECT_EQ(r.pixels.max_plane, -1);
  EXPECT_EQ(r.status, CompareStatus::kOk);
}

// With constant images the variances and covariance are 0, so SSIM is its luminance term
// (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1) with C1 = (0.01 L)^2, L = 1 (the reference peak).
TEST(CompareMetrics, SsimOfConstantOffsetIsTheLuminanceTerm) {
  const Image b(4, 3, 3, 1.0f);
  const Image a(4, 3, 3, 1.1f);
  const CompareResult r = compare_images(a, b, {{"rgb", {0, 1, 2}, true}}, CompareOptions{});
  // (2 * 1.1 + 1e-4) / (1 + 1.21 + 1e-4); 1e-6 covers 1.1f and the float luminance sum.
  EXPECT_NEAR(metric(r.layers[0], Metric::kSsim), 0.9954753178589205, 1e-6);
  EXPECT_NEAR(metric(r.overall, Metric::kSsim), 0.9954753178589205, 1e-6);
}

TEST(CompareMetrics, SsimOfOneByOneImageIsDefined) {
  const Image b(1, 1, 1, 2.0f);
  const Image a(1, 1, 1, 1.0f);
  const CompareResult r = compare_images(a, b, {{"Y", {0}, false}}, CompareOptions{});
  // L = 2: C1 = 4e-4; (2 * 2 + 4e-4) / (1 + 4 + 4e-4).
  EXPECT_NEAR(metric(r.layers[0], Metric::kSsim), (4.0 + 4e-4) / (5.0 + 4e-4), 1e-12);
}

TEST(CompareMetrics, SsimDropsWithStructureAndStaysInRange) {
  Image b(16, 16, 1), a(16, 16, 1);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      b.at(0, x, y) = ((x / 2 + y / 2) % 2) ? 1.0f : 0.2f;  // checker
      a.at(0, x, y) = 0.6f;                                 // its mean, no structure
    }
  }
  const double ssim =
      metric(compare_images(a, b, {{"Y", {0}, false}}, CompareOptions{}).layers[0], Metric::kSsim);
  EXPECT_GT(ssim, -1.0);
  EXPECT_LT(ssim, 0.1);  // contrast and structure terms are ~C2 / (sigma_b^2 + C2)
}

// Without a mask, a layer's background is where all its reference channels are exactly 0.
TEST(CompareBackground, ZeroReferencePixelsAreLeftOutOfTheMetricsButNotTheThresholds) {
  const Image b = image_from(2, 2, {{0, 2, 0, 4}});
  const Image a = image_from(2, 2, {{1, 2, 0, 5}});
  CompareResult r = compare_images(a, b, {{"Y", {0}, false}}, options_without_ssim());
  EXPECT_EQ(r.layers[0].foreground_pixels, 2u);
  EXPECT_NEAR(metric(r.layers[0], Metric::kRmse), 0.7071067811865476, kTight);  // sqrt(1 / 2)
  EXPECT_EQ(r.pixels.fail_pixels, 2u);  // pixel 0 (background) still counts

  CompareOptions all = options_without_ssim();
  all.exclude_zero_reference = false;
  r = compare_images(a, b, {{"Y", {0}, false}}, all);
  EXPECT_EQ(r.layers[0].foreground_pixels, 4u);
  EXPECT_NEAR(metric(r.layers[0], Metric::kRmse), 0.5 * std::sqrt(2.0), kTight);  // 2 / 4
}

TEST(CompareBackground, ExplicitMaskAppliesToEveryLayer) {
  const Image b = image_from(2, 2, {{1, 2, 3, 4}});
  const Image a = image_from(2, 2, {{9, 2, 3, 5}});
  const CompareResult r =
      compare_images(a, b, {{"Y", {0}, false}}, options_without_ssim(), {1, 0, 0, 0});
  EXPECT_EQ(r.layers[0].foreground_pixels, 3u);
  EXPECT_NEAR(metric(r.layers[0], Metric::kRmse), std::sqrt(1.0 / 3.0), kTight);
  EXPECT_DOUBLE_EQ(r.pixels.max_error, 8.0);
}

TEST(CompareBackground, DepthMarksBackgroundBeyondOneBillionOrNotFinite) {
  const float depth[] = {5.0f, 1e10f, kInfF, kNaN, -1e10f, 9.9e8f};
  EXPECT_EQ(background_from_depth(depth, 6), (std::vector<std::uint8_t>{0, 1, 1, 1, 1, 0}));
}

TEST(CompareMetrics, NonFiniteSamplesAreCountedNotAveraged) {
  const Image b = image_from(2, 2, {{1, 2, kNaN, 4}});
  const Image a = image_from(2, 2, {{kNaN, 2, kNaN, 4}});
  const CompareResult r = compare_images(a, b, {{"Y", {0}, false}}, options_without_ssim());
  EXPECT_EQ(r.layers[0].nonfinite_samples, 2u);
  EXPECT_EQ(r.layers[0].samples, 2u);
  EXPECT_EQ(metric(r.layers[0], Metric::kRmse), 0.0);
  // NaN against 1 differs infinitely; NaN against NaN does not differ.
  EXPECT_TRUE(std::isinf(r.pixels.max_error));
  EXPECT_EQ(r.pixels.fail_pixels, 1u);
  EXPECT_EQ(r.pixels.max_x, 0);
}

TEST(CompareMetrics, UndefinedMetricsAreEmpty) {
  const Image zero(2, 2, 1, 0.0f);
  CompareOptions options;
  options.exclude_zero_reference = false;
  const CompareResult r = compare_images(zero, zero, {{"Y", {0}, false}}, options);
  EXPECT_EQ(metric(r.layers[0], Metric::kRmse), 0.0);
  EXPECT_FALSE(r.layers[0].metric(Metric::kRelRmse).has_value());  // mean(b) = 0
  EXPECT_FALSE(r.layers[0].metric(Metric::kPsnr).has_value());     // peak = 0
  EXPECT_NEAR(metric(r.layers[0], Metric::kSsim), 1.0, 1e-12);     // L falls back to 1

  // All background: nothing is defined.
  const CompareResult none = compare_images(zero, zero, {{"Y", {0}, false}}, CompareOptions{});
  for (const auto& m : none.layers[0].metrics) EXPECT_FALSE(m.has_value());
}

TEST(CompareMetrics, DifferenceImageIsScaledAbsoluteDifference) {
  const Image b = image_from(2, 1, {{1, kInfF}, {kNaN, 3}});
  const Image a = image_from(2, 1, {{0.5f, kInfF}, {kNaN, 1}});
  const Image d = difference_image(a, b, 4.0f);
  EXPECT_EQ(d.at(0, 0, 0), 2.0f);
  EXPECT_EQ(d.at(0, 1, 0), 0.0f);  // the same infinity
  EXPECT_EQ(d.at(1, 0, 0), 0.0f);  // both NaN
  EXPECT_EQ(d.at(1, 1, 0), 8.0f);
}

TEST(CompareThresholds, FailWhenMoreThanFailPercentOfPixelsFail) {
  Thresholds t;
  t.fail = 0.1;
  t.fail_percent = 5;
  t.warn_percent = 100;  // isolate the fail rule
  PixelDiffStats d;
  d.pixels = 100;
  d.max_error = 0.2;
  d.fail_pixels = 5;  // exactly 5%: not more than
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kOk);
  d.fail_pixels = 6;
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kFail);
}

TEST(CompareThresholds, HardFailOnAnySinglePixel) {
  Thresholds t;
  t.fail_percent = 100;
  t.warn_percent = 100;
  t.hard_fail = 0.25;
  PixelDiffStats d;
  d.pixels = 1000;
  d.fail_pixels = d.warn_pixels = 1;
  d.max_error = 0.25;  // not above
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kOk);
  d.max_error = 0.26;
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kFail);
}

TEST(CompareThresholds, WarnBetweenWarnAndFailPercents) {
  Thresholds t;  // idiff's example: -fail 0.004 -failpercent 10 -warn 0.004 -warnpercent 3
  t.warn = t.fail = 0.004;
  t.warn_percent = 3;
  t.fail_percent = 10;
  PixelDiffStats d;
  d.pixels = 100;
  d.warn_pixels = d.fail_pixels = 3;
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kOk);
  d.warn_pixels = d.fail_pixels = 4;
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kWarn);
  d.warn_pixels = d.fail_pixels = 11;
  EXPECT_EQ(evaluate_thresholds(d, t), CompareStatus::kFail);
}

TEST(CompareThresholds, DefaultsFailOnAnyDifferenceAboveOneMillionth) {
  PixelDiffStats d;
  d.pixels = 1'000'000;
  EXPECT_EQ(evaluate_thresholds(d, Thresholds{}), CompareStatus::kOk);
  d.fail_pixels = d.warn_pixels = 1;
  EXPECT_EQ(evaluate_thresholds(d, Thresholds{}), CompareStatus::kFail);
}

TEST(CompareThresholds, CountsUseTheLargestChannelDifferenceOfEachPixel) {
  const Image b(2, 1, 2, 1.0f);
  const Image a = image_from(2, 1, {{1.01f, 1.0f}, {1.0f, 1.2f}});
  CompareOptions options = options_without_ssim();
  options.thresholds.warn = 0.005;
  options.thresholds.fail = 0.1;
  options.thresholds.fail_percent = 49;
  const CompareResult r = compare_images(a, b, {{"xy", {0, 1}, false}}, options);
  EXPECT_EQ(r.pixels.warn_pixels, 2u);
  EXPECT_EQ(r.pixels.fail_pixels, 1u);  // 50% > 49%
  EXPECT_EQ(r.status, CompareStatus::kFail);
}

TEST(CompareSummary, MeanWorstAndWorstFrame) {
  auto frame = [](double rmse, double psnr, CompareStatus status) {
    CompareResult r;
    r.layers.push_back(LayerStats{});
    r.layers[0].name = "indirect";
    r.layers[0].metrics[static_cast<int>(Metric::kRmse)] = rmse;
    r.layers[0].metrics[static_cast<int>(Metric::kPsnr)] = psnr;
    r.overall = r.layers[0];
    r.overall.name = "all";
    r.status = status;
    return r;
  };
  const SequenceSummary s =
      summarize_frames({frame(0.1, 30, CompareStatus::kOk), frame(0.3, 20, CompareStatus::kWarn),
                        frame(0.2, 25, CompareStatus::kWarn)});
  ASSERT_EQ(s.layers.size(), 1u);
  const MetricSummary& rmse = s.layers[0].metrics[static_cast<int>(Metric::kRmse)];
  EXPECT_NEAR(*rmse.mean, 0.2, 1e-15);
  EXPECT_EQ(*rmse.worst, 0.3);
  EXPECT_EQ(rmse.worst_index, 1);
  const MetricSummary& psnr = s.overall.metrics[static_cast<int>(Metric::kPsnr)];
  EXPECT_EQ(*psnr.worst, 20.0);  // lower PSNR is worse
  EXPECT_FALSE(s.overall.metrics[static_cast<int>(Metric::kSsim)].mean.has_value());
  EXPECT_EQ(s.status, CompareStatus::kWarn);
  EXPECT_EQ(s.worst_index, 1);  // a warning, and the larger RMSE of the two
  EXPECT_EQ(s.status_counts, (std::array<int, 3>{1, 2, 0}));
}

TEST(CompareMetricList, ParsesNamesAndAll) {
  EXPECT_EQ(parse_metric_list("psnr,rmse,psnr"),
            (std::vector<Metric>{Metric::kPsnr, Metric::kRmse}));
  EXPECT_EQ(parse_metric_list("all").size(), 5u);
  try {
    parse_metric_list("rmse,flip");
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
  }
}

FileChannels single_part(std::vector<std::string> names) {
  FileChannels f;
  f.subimage_names = {""};
  f.channels = {std::move(names)};
  return f;
}

TEST(CompareSelectLayers, DefaultIsEveryRgbLayerBothFilesHave) {
  const FileChannels a = single_part({"A", "B", "G", "R", "gi.B", "gi.G", "gi.R", "indirect.B",
                                      "indirect.G", "indirect.R", "depth.Z"});
  const FileChannels b = single_part({"R", "G", "B", "indirect.R", "indirect.G", "indirect.B"});
  const std::vector<LayerChannels> layers = select_layers("a.exr", a, "b.exr", b, {});
  ASSERT_EQ(layers.size(), 2u);
  EXPECT_EQ(layers[0].name, "R,G,B");  // the root layer
  EXPECT_EQ(layers[0].a, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_TRUE(layers[0].rgb);
  EXPECT_EQ(layers[1].name, "indirect");
  EXPECT_EQ(layers[1].b, (std::vector<std::string>{"indirect.R", "indirect.G", "indirect.B"}));
}

TEST(CompareSelectLayers, ItemsNameChannelsLayersAndPairs) {
  const FileChannels a = single_part({"indirect.R", "indirect.G", "indirect.B", "Z", "R", "G"});
  const FileChannels b = single_part(
      {"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B", "Z", "R", "G"});
  const std::vector<LayerChannels> layers =
      select_layers("a.exr", a, "b.exr", b, {"indirect=ViewLayer.DiffInd", "R", "G", "Z"});
  ASSERT_EQ(layers.size(), 2u);
  EXPECT_EQ(layers[0].name, "indirect=ViewLayer.DiffInd");
  EXPECT_EQ(layers[0].b[2], "ViewLayer.DiffInd.B");
  EXPECT_TRUE(layers[0].rgb);
  EXPECT_EQ(layers[1].name, "R,G,Z");  // root channels group together
  EXPECT_FALSE(layers[1].rgb);
}

TEST(CompareSelectLayers, PlainChannelsOfNamedPartsTakeThePartName) {
  FileChannels a;
  a.subimage_names = {"beauty", "indirect"};
  a.channels = {{"R", "G", "B"}, {"B", "G", "R"}};
  const FileChannels b =
      single_part({"beauty.R", "beauty.G", "beauty.B", "indirect.R", "indirect.G", "indirect.B"});
  const std::vector<LayerChannels> layers = select_layers("a.exr", a, "b.exr", b, {});
  ASSERT_EQ(layers.size(), 2u);
  EXPECT_EQ(layers[0].name, "beauty");
  EXPECT_EQ(layers[1].name, "indirect");
}

TEST(CompareSelectLayers, MismatchesAreInputErrorsNamingTheFile) {
  const FileChannels a = single_part({"indirect.R", "indirect.G", "indirect.B"});
  const FileChannels b = single_part({"R", "G", "B"});
  try {
    select_layers("a.exr", a, "b.exr", b, {});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
    EXPECT_EQ(e.file(), "b.exr");
  }
  try {
    select_layers("a.exr", a, "b.exr", b, {"indirect.A"});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
    EXPECT_EQ(e.file(), "a.exr");
  }
  try {
    select_layers("a.exr", a, "b.exr", b, {"indirect=R"});  // 3 channels against 1
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
  }
  try {
    select_layers("a.exr", a, "b.exr", b, {"=R"});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
  }
}

// Small EXR files in a fresh directory, removed afterwards.
class CompareFiles : public ::testing::Test {
 protected:
  struct Channel {
    std::string name;
    std::vector<float> pixels;
  };

  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("ssgi_compare_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Writes `parts` (one entry: single-part) of w x h float channels; channel order as given,
  // which OpenEXR sorts by name on disk.
  std::string write(const std::string& name, int w, int h,
                    const std::vector<std::pair<std::string, std::vector<Channel>>>& parts) {
    const std::string file = path(name);
    std::vector<OIIO::ImageSpec> specs;
    for (const auto& [part, channels] : parts) {
      OIIO::ImageSpec spec(w, h, static_cast<int>(channels.size()), OIIO::TypeDesc::FLOAT);
      spec.channelnames.clear();
      spec.alpha_channel = spec.z_channel = -1;
      for (const Channel& c : channels) spec.channelnames.push_back(c.name);
      if (!part.empty()) spec.attribute("oiio:subimagename", part);
      specs.push_back(spec);
    }
    auto out = OIIO::ImageOutput::create(file);
    EXPECT_TRUE(out && out->open(file, static_cast<int>(specs.size()), specs.data()));
    for (std::size_t s = 0; s < parts.size(); ++s) {
      if (s > 0) {
        EXPECT_TRUE(out->open(file, specs[s], OIIO::ImageOutput::AppendSubimage));
      }
      const auto& channels = parts[s].second;
      const std::size_t n = channels.size(), npix = static_cast<std::size_t>(w) * h;
      std::vector<float> interleaved(npix * n);
      for (std::size_t c = 0; c < n; ++c)
        for (std::size_t p = 0; p < npix; ++p) interleaved[p * n + c] = channels[c].pixels[p];
      EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()));
    }
    out->close();
    return file;
  }

  // A 4x4 `indirect` layer of value v (+ delta at pixel (1, 2) in G) and a depth layer.
  std::string write_gi(const std::string& name, float v, float delta = 0.0f, int size = 4,
                       bool rgb_order = true) {
    const std::size_t n = static_cast<std::size_t>(size) * size;
    std::vector<float> g(n, v);
    if (delta != 0.0f) g[2 * size + 1] += delta;
    std::vector<Channel> channels = {{"indirect.R", std::vector<float>(n, v)},
                                     {"indirect.G", g},
                                     {"indirect.B", std::vector<float>(n, v)},
                                     {"depth.Z", std::vector<float>(n, 2.0f)}};
    if (!rgb_order) std::swap(channels[0], channels[2]);
    return write(name, size, size, {{"", channels}});
  }

  // Runs the built CLI; returns its exit code and stdout.
  static int run(const std::string& args, std::string* out = nullptr) {
    const std::string command = std::string(SSGI_BINARY) + " compare " + args + " 2>/dev/null";
    FILE* pipe = ::popen(command.c_str(), "r");
    std::string text;
    char buf[4096];
    while (std::size_t got = std::fread(buf, 1, sizeof buf, pipe)) text.append(buf, got);
    const int status = ::pclose(pipe);
    if (out) *out = text;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  fs::path dir_;
};

TEST_F(CompareFiles, ChannelsAreMatchedByNameWhateverTheirOrder) {
  const std::string a = write_gi("a.exr", 0.5f);
  const std::string b = write_gi("b.exr", 0.5f, 0.0f, 4, /*rgb_order=*/false);
  const FileCompareResult r = compare_files(a, b, FileCompareOptions{});
  ASSERT_EQ(r.layers.size(), 1u);
  EXPECT_EQ(r.layers[0].name, "indirect");
  EXPECT_EQ(r.depth_channel, "depth.Z");
  EXPECT_EQ(r.result.status, CompareStatus::kOk);
  EXPECT_EQ(metric(r.result.overall, Metric::kRmse), 0.0);
}

TEST_F(CompareFiles, DifferenceIsLocatedAndWrittenAtomically) {
  const std::string a = write_gi("a.exr", 0.5f, 0.25f);
  const std::string b = write_gi("b.exr", 0.5f);
  FileCompareOptions options;
  options.diff_path = path("diff.exr");
  options.diff_scale = 2.0f;
  const FileCompareResult r = compare_files(a, b, options);
  EXPECT_EQ(r.result.status, CompareStatus::kFail);
  EXPECT_EQ(r.result.pixels.fail_pixels, 1u);
  EXPECT_EQ(r.result.pixels.max_x, 1);
  EXPECT_EQ(r.result.pixels.max_y, 2);
  EXPECT_EQ(r.plane_names[r.result.pixels.max_plane], "indirect.G");
  // One of 48 samples is 0.25 off: RMSE = 0.25 / sqrt(48).
  EXPECT_NEAR(metric(r.result.overall, Metric::kRmse), 0.25 / std::sqrt(48.0), 1e-9);

  auto in = OIIO::ImageInput::open(options.diff_path);
  ASSERT_TRUE(in);
  const int g = in->spec().channelindex("indirect.G");
  ASSERT_GE(g, 0);
  EXPECT_EQ(in->spec().nchannels, 3);
  std::vector<float> pixels(16);
  ASSERT_TRUE(in->read_image(0, 0, g, g + 1, OIIO::TypeDesc::FLOAT, pixels.data()));
  EXPECT_EQ(pixels[2 * 4 + 1], 0.5f);  // (1, 2): 0.25 * 2
  EXPECT_EQ(pixels[0], 0.0f);
  in->close();
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) files += entry.is_regular_file();
  EXPECT_EQ(files, 3);  // a, b, diff: no temporary left behind
}

TEST_F(CompareFiles, DepthBackgroundIsLeftOutOfTheMetrics) {
  std::vector<float> depth(4, 3.0f), ref = {1, 1, 1, 1}, out = {1, 1, 1, 9};
  depth[3] = 1e10f;
  const std::string a = write("a.exr", 2, 2, {{"", {{"Y", out}}}});
  const std::string b = write("b.exr", 2, 2, {{"", {{"Y", ref}, {"Z", depth}}}});
  FileCompareOptions options;
  options.channels = {"Y"};
  FileCompareResult r = compare_files(a, b, options);
  EXPECT_EQ(r.depth_channel, "Z");
  EXPECT_EQ(metric(r.result.overall, Metric::kRmse), 0.0);
  EXPECT_EQ(r.result.status, CompareStatus::kFail);  // thresholds see every pixel

  options.all_pixels = true;
  r = compare_files(a, b, options);
  EXPECT_EQ(metric(r.result.overall, Metric::kRmse), 4.0);  // sqrt(64 / 4)
}

TEST_F(CompareFiles, MultiPartChannelsAreFoundInAnyPart) {
  const std::vector<float> v(4, 0.25f);
  const std::string a = write("a.exr", 2, 2,
                              {{"beauty", {{"R", v}, {"G", v}, {"B", v}}},
                               {"gi", {{"gi.R", v}, {"gi.G", v}, {"gi.B", v}}}});
  const std::string b = write("b.exr", 2, 2,
                              {{"",
                                {{"beauty.R", v},
                                 {"beauty.G", v},
                                 {"beauty.B", v},
                                 {"gi.R", v},
                                 {"gi.G", v},
                                 {"gi.B", v}}}});
  const FileCompareResult r = compare_files(a, b, FileCompareOptions{});
  ASSERT_EQ(r.layers.size(), 2u);
  EXPECT_EQ(r.layers[0].name, "beauty");
  EXPECT_EQ(r.layers[1].name, "gi");
  EXPECT_EQ(r.result.status, CompareStatus::kOk);
}

TEST_F(CompareFiles, SizeMismatchIsAnInputErrorAndMissingFileAnIoError) {
  const std::string a = write_gi("a.exr", 0.5f);
  const std::string big = write_gi("big.exr", 0.5f, 0.0f, 8);
  try {
    compare_files(a, big, FileCompareOptions{});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
  }
  try {
    compare_files(a, path("missing.exr"), FileCompareOptions{});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIO);
    EXPECT_EQ(e.file(), path("missing.exr"));
  }
  FileCompareOptions options;
  options.depth_channel = "nope.Z";
  try {
    compare_files(a, a, options);
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
  }
}

TEST_F(CompareFiles, CliExitCodes) {
  const std::string a = write_gi("a.exr", 0.5f);
  const std::string same = write_gi("same.exr", 0.5f);
  const std::string near = write_gi("near.exr", 0.5f, 0.01f);
  const std::string far = write_gi("far.exr", 0.5f, 0.5f);
  const std::string big = write_gi("big.exr", 0.5f, 0.0f, 8);
  const std::string thresholds = " --warn 0.001 --fail 0.1 ";
  EXPECT_EQ(run(a + " " + same), 0);
  EXPECT_EQ(run(thresholds + near + " " + a), 1);
  EXPECT_EQ(run(thresholds + far + " " + a), 2);
  EXPECT_EQ(run(thresholds + "--hardfail 0.005 " + near + " " + a), 2);
  EXPECT_EQ(run(thresholds + "--failpercent 10 " + far + " " + a), 1);  // 1 of 16 pixels
  EXPECT_EQ(run(a + " " + big), 3);
  EXPECT_EQ(run("--channels beauty " + a + " " + same), 3);
  EXPECT_EQ(run(a + " " + path("missing.exr")), 4);
  EXPECT_EQ(run("--bogus " + a + " " + same), 2);
  EXPECT_EQ(run("--metric flip " + a + " " + same), 2);
  EXPECT_EQ(run("--failpercent 101 " + a + " " + same), 2);
  EXPECT_EQ(run(a), 2);
  EXPECT_EQ(run("--help"), 0);
}

TEST_F(CompareFiles, CliSequenceJsonAndDiffPattern) {
  write_gi("out.0001.exr", 0.5f);
  write_gi("out.0002.exr", 0.5f, 0.5f);
  write_gi("out.0003.exr", 0.5f, 0.01f);
  for (const char* f : {"ref.0001.exr", "ref.0002.exr", "ref.0003.exr"}) write_gi(f, 0.5f);
  std::string text;
  const int code =
      run("--json --warn 0.001 --fail 0.1 --metric rmse,psnr --diff " + path("diff.####.exr") +
              " " + path("out.####.exr") + " " + path("ref.####.exr"),
          &text);
  EXPECT_EQ(code, 2);
  const nlohmann::json j = nlohmann::json::parse(text);
  ASSERT_EQ(j["frames"].size(), 3u);
  EXPECT_EQ(j["frames"][0]["status"], "ok");
  EXPECT_TRUE(j["frames"][0]["overall"]["psnr"].is_null());  // identical: infinite
  EXPECT_EQ(j["frames"][1]["status"], "fail");
  EXPECT_EQ(j["frames"][2]["status"], "warn");
  EXPECT_FALSE(j["frames"][1]["overall"].contains("ssim"));
  EXPECT_EQ(j["summary"]["worst_frame"], 2);
  EXPECT_EQ(j["summary"]["status"], "fail");
  EXPECT_EQ(j["summary"]["overall"]["rmse"]["worst_frame"], 2);
  for (const char* f : {"diff.0001.exr", "diff.0002.exr", "diff.0003.exr"})
    EXPECT_TRUE(fs::exists(path(f))) << f;

  // A missing frame is a file error (4) that outranks the failure; the rest are still compared.
  fs::remove(path("ref.0003.exr"));
  EXPECT_EQ(run("--frames 1-3 " + path("out.####.exr") + " " + path("ref.####.exr"), &text), 4);
  EXPECT_NE(text.find("error"), std::string::npos);
  EXPECT_EQ(run("--frames 1 " + path("out.####.exr") + " " + path("ref.####.exr")), 0);
}

}  // namespace
}  // namespace ssgi
