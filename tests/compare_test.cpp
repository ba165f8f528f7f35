// Tests of `ssgi compare`: metrics against values worked out by hand on tiny images, idiff's
// threshold rules, channel selection by name, and the CLI's exit codes on small EXRs.
#include "compare/compare.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "compare/compare_files.h"
#include "options/compare_options.h"
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
  EXPECT_DOUBLE_EQ(r.overall.max_error, 1.0);
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
  EXPECT_EQ(s.max_error, 0.0);
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
TEST(CompareBackground, ZeroReferencePixelsAreLeftOutOfTheMetrics) {
  const Image b = image_from(2, 2, {{0, 2, 0, 4}});
  const Image a = image_from(2, 2, {{1, 2, 0, 5}});
  CompareResult r = compare_images(a, b, {{"Y", {0}, false}}, options_without_ssim());
  EXPECT_EQ(r.layers[0].foreground_pixels, 2u);
  EXPECT_NEAR(metric(r.layers[0], Metric::kRmse), 0.7071067811865476, kTight);  // sqrt(1 / 2)
  EXPECT_DOUBLE_EQ(r.layers[0].max_error, 1.0);  // pixel 0 (background) still counts here

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
  EXPECT_DOUBLE_EQ(r.layers[0].max_error, 8.0);
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
  EXPECT_TRUE(std::isinf(r.layers[0].max_error));
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

WindowedImage windowed(int x0, int y0, int w, int h,
                       const std::vector<std::vector<float>>& planes) {
  WindowedImage image;
  image.window = {x0, y0, x0 + w, y0 + h};
  image.pixels = image_from(w, h, planes);
  for (std::size_t c = 0; c < planes.size(); ++c)
    image.channel_names.push_back("c" + std::to_string(c));
  return image;
}

// ImageBufAlgo::compare's sums over the union of the windows and channels: a is 2x1 at (0, 0)
// with one channel, b 2x1 at (1, 0) with two; the union is 3x1 x 2 channels, 6 samples, and
// what a window or channel lacks is 0.
TEST(Idiff, NumbersOverTheUnionOfWindowsAndChannels) {
  const WindowedImage a = windowed(0, 0, 2, 1, {{0.5f, 0.25f}});
  const WindowedImage b = windowed(1, 0, 2, 1, {{0.25f, 2.0f}, {0.0f, 0.125f}});
  const IdiffStats d = idiff_compare(a, b, IdiffThresholds{});
  // |differences|: x=0: 0.5, 0; x=1: 0, 0; x=2: 2, 0.125.
  EXPECT_DOUBLE_EQ(d.mean_error, 2.625 / 6);
  EXPECT_DOUBLE_EQ(d.rms_error, std::sqrt((0.25 + 4.0 + 0.015625) / 6));
  EXPECT_DOUBLE_EQ(d.psnr, 20.0 * std::log10(2.0 / d.rms_error));  // peak: max |value| = 2
  EXPECT_EQ(d.max_error, 2.0);
  EXPECT_EQ(d.max_x, 2);
  EXPECT_EQ(d.max_y, 0);
  EXPECT_EQ(d.max_channel, 0);
  EXPECT_EQ(d.warn_pixels, 2u);  // pixels, not samples
  EXPECT_EQ(d.fail_pixels, 2u);
}

TEST(Idiff, PeakIsOneForImagesInTheUnitRangeAndIdenticalImagesHaveInfinitePsnr) {
  const WindowedImage a = windowed(0, 0, 2, 1, {{0.5f, 0.25f}});
  const WindowedImage b = windowed(0, 0, 2, 1, {{0.5f, 0.75f}});
  EXPECT_DOUBLE_EQ(idiff_compare(a, b, {}).psnr, 20.0 * std::log10(1.0 / std::sqrt(0.125)));
  const IdiffStats same = idiff_compare(a, a, {});
  EXPECT_EQ(same.max_error, 0.0);
  EXPECT_TRUE(std::isinf(same.psnr));
}

// Thresholds are floats: 0.25f + 0.01f - 0.25f is 0.00999999, not over 0.01f; 0.02 is.
TEST(Idiff, ThresholdsCompareFloatDifferencesWithFloatLimitsAndRelativeLimits) {
  const WindowedImage b = windowed(0, 0, 3, 1, {{0.25f, 0.25f, 4.0f}});
  const WindowedImage a = windowed(0, 0, 3, 1, {{0.25f + 0.01f, 0.27f, 4.02f}});
  IdiffThresholds t;
  t.warn = t.fail = 0.01f;
  IdiffStats d = idiff_compare(a, b, t);
  EXPECT_EQ(d.warn_pixels, 2u);
  t.fail_relative = 0.01f;  // 0.02 / 4.01 is below 1% of the mean magnitude, 0.02 / 0.26 not
  d = idiff_compare(a, b, t);
  EXPECT_EQ(d.fail_pixels, 1u);
  EXPECT_EQ(d.warn_pixels, 2u);
}

// OIIO 2.4's non-finite rules: NaN matches NaN and an infinity any infinity; the first other
// mismatch sets the max error to inf without counting the pixel; the next goes into the sums.
TEST(Idiff, NonFiniteValuesAsOiio) {
  const float nan = kNaN, inf = kInfF;
  WindowedImage a = windowed(0, 0, 4, 1, {{nan, inf, 0.5f, 0.5f}});
  WindowedImage b = windowed(0, 0, 4, 1, {{nan, -inf, 0.5f, 0.5f}});
  IdiffStats d = idiff_compare(a, b, {});
  EXPECT_EQ(d.max_error, 0.0);
  EXPECT_EQ(d.fail_pixels, 0u);

  b = windowed(0, 0, 4, 1, {{0.5f, 0.5f, inf, 0.5f}});
  a = windowed(0, 0, 4, 1, {{nan, 0.5f, 0.5f, 0.5f}});
  d = idiff_compare(a, b, {});
  EXPECT_TRUE(std::isinf(d.max_error));
  EXPECT_EQ(d.max_x, 0);
  EXPECT_EQ(d.fail_pixels, 1u);  // the NaN at x=0 is not counted; the inf at x=2 is
  EXPECT_TRUE(std::isinf(d.mean_error));
}

IdiffStats counts(std::size_t fail, std::size_t warn, double max_error) {
  IdiffStats d;
  d.fail_pixels = fail;
  d.warn_pixels = warn;
  d.max_error = max_error;
  return d;
}

// idiff 2.4: nothing fails or warns unless more than -allowfailures pixels fail.
TEST(Idiff, WithoutFailingPixelsThereIsNoWarningAndNoHardFailure) {
  IdiffThresholds t;
  t.warn = 0.01f;
  t.fail = 1.0f;
  t.hard_fail = 0.03f;
  t.hard_warn = 0.02f;
  EXPECT_EQ(idiff_status(counts(0, 100, 0.5), 100, t, CompareStatus::kOk), CompareStatus::kOk);
  EXPECT_EQ(idiff_status(counts(1, 100, 0.5), 100, t, CompareStatus::kOk), CompareStatus::kFail);
  t.allow_failures = 1;
  EXPECT_EQ(idiff_status(counts(1, 100, 0.5), 100, t, CompareStatus::kOk), CompareStatus::kOk);
  // And it keeps the verdict of earlier subimages.
  EXPECT_EQ(idiff_status(counts(1, 100, 0.5), 100, t, CompareStatus::kWarn), CompareStatus::kWarn);
}

TEST(Idiff, FailPercentThenWarnPercentOfThePixelCount) {
  IdiffThresholds t;  // idiff's example: -fail 0.004 -failpercent 10 -warn 0.004 -warnpercent 3
  t.warn = t.fail = 0.004f;
  t.warn_percent = 3;
  t.fail_percent = 10;
  EXPECT_EQ(idiff_status(counts(3, 3, 1), 100, t, CompareStatus::kOk), CompareStatus::kOk);
  EXPECT_EQ(idiff_status(counts(4, 4, 1), 100, t, CompareStatus::kOk), CompareStatus::kWarn);
  EXPECT_EQ(idiff_status(counts(10, 10, 1), 100, t, CompareStatus::kOk), CompareStatus::kWarn);
  EXPECT_EQ(idiff_status(counts(11, 11, 1), 100, t, CompareStatus::kOk), CompareStatus::kFail);
  EXPECT_EQ(idiff_status(counts(4, 4, 1), 100, t, CompareStatus::kFail), CompareStatus::kFail);
  t.hard_warn = 0.5f;  // over it, with failing pixels but within the percents: a warning
  EXPECT_EQ(idiff_status(counts(1, 1, 1), 100, t, CompareStatus::kOk), CompareStatus::kWarn);
  t.hard_fail = 0.5f;
  EXPECT_EQ(idiff_status(counts(1, 1, 1), 100, t, CompareStatus::kOk), CompareStatus::kFail);
}

TEST(CompareSummary, MeanWorstAndWorstFrame) {
  auto frame = [](double rmse, double psnr) {
    CompareResult r;
    r.layers.push_back(LayerStats{});
    r.layers[0].name = "indirect";
    r.layers[0].metrics[static_cast<int>(Metric::kRmse)] = rmse;
    r.layers[0].metrics[static_cast<int>(Metric::kPsnr)] = psnr;
    r.overall = r.layers[0];
    r.overall.name = "all";
    return r;
  };
  const SequenceSummary s = summarize_frames({frame(0.1, 30), frame(0.3, 20), frame(0.2, 25)});
  ASSERT_EQ(s.layers.size(), 1u);
  const MetricSummary& rmse = s.layers[0].metrics[static_cast<int>(Metric::kRmse)];
  EXPECT_NEAR(*rmse.mean, 0.2, 1e-15);
  EXPECT_EQ(*rmse.worst, 0.3);
  EXPECT_EQ(rmse.worst_index, 1);
  const MetricSummary& psnr = s.overall.metrics[static_cast<int>(Metric::kPsnr)];
  EXPECT_EQ(*psnr.worst, 20.0);  // lower PSNR is worse
  EXPECT_FALSE(s.overall.metrics[static_cast<int>(Metric::kSsim)].mean.has_value());
}

TEST(CompareMetricList, ParsesNamesAndAll) {
  EXPECT_EQ(ssgi_cli::parse_metric_list("psnr,rmse,psnr"),
            (std::vector<Metric>{Metric::kPsnr, Metric::kRmse}));
  EXPECT_EQ(ssgi_cli::parse_metric_list("all").size(), 5u);
  try {
    ssgi_cli::parse_metric_list("rmse,flip");
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

  // Writes `parts` (one entry: single-part) of w x h float channels with the data window at
  // (x0, y0); channel order as given, which OpenEXR sorts by name on disk.
  std::string write(const std::string& name, int w, int h,
                    const std::vector<std::pair<std::string, std::vector<Channel>>>& parts,
                    int x0 = 0, int y0 = 0) {
    const std::string file = path(name);
    std::vector<OIIO::ImageSpec> specs;
    for (const auto& [part, channels] : parts) {
      OIIO::ImageSpec spec(w, h, static_cast<int>(channels.size()), OIIO::TypeDesc::FLOAT);
      spec.x = x0;
      spec.y = y0;
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
  EXPECT_EQ(metric(r.result.overall, Metric::kRmse), 0.0);
}

TEST_F(CompareFiles, IdiffDifferenceIsLocatedAndWrittenAtomically) {
  const std::string a = write_gi("a.exr", 0.5f, 0.25f);
  const std::string b = write_gi("b.exr", 0.5f);
  IdiffOptions options;
  options.diff_path = path("diff.exr");
  options.diff_scale = 2.0f;
  const IdiffFileResult r = idiff_files(b, a, options);
  EXPECT_EQ(r.status, CompareStatus::kFail);
  ASSERT_EQ(r.subimages.size(), 1u);
  const IdiffSubimage& s = r.subimages[0];
  EXPECT_EQ(s.stats.fail_pixels, 1u);
  EXPECT_EQ(s.stats.max_x, 1);
  EXPECT_EQ(s.stats.max_y, 2);
  EXPECT_EQ(s.max_channel_name, "indirect.G");
  std::vector<float> values = s.a_values;  // every channel, depth.Z too, in the file's order
  std::sort(values.begin(), values.end());
  EXPECT_EQ(values, (std::vector<float>{0.5f, 0.5f, 0.5f, 2.0f}));
  // One of 64 samples (4 channels: depth.Z too) is 0.25 off.
  EXPECT_DOUBLE_EQ(s.stats.rms_error, 0.25 / 8.0);
  EXPECT_TRUE(r.diff_written);

  auto in = OIIO::ImageInput::open(options.diff_path);
  ASSERT_TRUE(in);
  const int g = in->spec().channelindex("indirect.G");
  ASSERT_GE(g, 0);
  EXPECT_EQ(in->spec().nchannels, 4);
  std::vector<float> pixels(16);
  ASSERT_TRUE(in->read_image(0, 0, g, g + 1, OIIO::TypeDesc::FLOAT, pixels.data()));
  EXPECT_EQ(pixels[2 * 4 + 1], -0.5f);  // (1, 2): (0.5 - 0.75) * 2, signed as idiff -o
  EXPECT_EQ(pixels[0], 0.0f);
  in->close();
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) files += entry.is_regular_file();
  EXPECT_EQ(files, 3);  // a, b, diff: no temporary left behind

  // -od writes nothing for identical images; -abs makes it |A - B|.
  fs::remove(options.diff_path);
  options.diff_only_if_different = true;
  EXPECT_FALSE(idiff_files(a, a, options).diff_written);
  EXPECT_FALSE(fs::exists(options.diff_path));
  options.diff_abs = true;
  EXPECT_TRUE(idiff_files(b, a, options).diff_written);
  in = OIIO::ImageInput::open(options.diff_path);
  ASSERT_TRUE(in && in->read_image(0, 0, g, g + 1, OIIO::TypeDesc::FLOAT, pixels.data()));
  EXPECT_EQ(pixels[2 * 4 + 1], 0.5f);
}

TEST_F(CompareFiles, IdiffChannelsPairsByNameAcrossParts) {
  const std::vector<float> v(4, 0.25f), w = {0.25f, 0.25f, 0.25f, 0.5f};
  const std::string a = write("a.exr", 2, 2,
                              {{"beauty", {{"R", v}, {"G", v}, {"B", v}}},
                               {"gi", {{"gi.R", v}, {"gi.G", v}, {"gi.B", w}}}});
  const std::string b = write("b.exr", 2, 2, {{"", {{"X.R", v}, {"X.G", v}, {"X.B", v}}}});
  IdiffOptions options;
  options.channels = {"gi=X"};
  const IdiffFileResult r = idiff_files(a, b, options);
  ASSERT_EQ(r.subimages.size(), 1u);
  EXPECT_EQ(r.subimages[0].channels, 3);
  EXPECT_EQ(r.subimages[0].max_channel_name, "gi.B");
  EXPECT_EQ(r.subimages[0].stats.max_x, 1);
  EXPECT_EQ(r.subimages[0].stats.max_y, 1);
  options.channels = {"beauty=X"};
  EXPECT_EQ(idiff_files(a, b, options).status, CompareStatus::kOk);
  options.all_subimages = true;
  try {
    idiff_files(a, b, options);
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
  }
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
  EXPECT_DOUBLE_EQ(r.result.overall.max_error, 8.0);  // the background pixel

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
  EXPECT_EQ(metric(r.result.overall, Metric::kRmse), 0.0);
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
  // As idiff 2.4: no pixel over -fail, no warning and no hard failure.
  EXPECT_EQ(run(thresholds + near + " " + a), 0);
  EXPECT_EQ(run(thresholds + "--hardfail 0.005 " + near + " " + a), 0);
  EXPECT_EQ(run("-warn 0.001 -fail 0.005 -failpercent 10 " + near + " " + a), 1);
  EXPECT_EQ(run("-warn 0.001 -fail 0.005 -failpercent 10 -hardfail 0.009 " + near + " " + a), 2);
  EXPECT_EQ(run(thresholds + far + " " + a), 2);
  EXPECT_EQ(run(thresholds + "--failpercent 10 " + far + " " + a), 1);  // 1 of 16 pixels
  EXPECT_EQ(run("-allowfailures 1 " + far + " " + a), 0);
  // Sizes differ: idiff compares the union of the windows, black outside (a failure here).
  EXPECT_EQ(run(a + " " + big), 2);
  EXPECT_EQ(run("--metric rmse " + a + " " + big), 3);  // ssgi's metrics need equal windows
  EXPECT_EQ(run("--channels beauty " + a + " " + same), 3);
  EXPECT_EQ(run("-p " + a + " " + same), 2);
  EXPECT_EQ(run("-allowfailures -1 " + a + " " + same), 2);
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
      run("--json -warn 0.001 -fail 0.005 -failpercent 10 -hardfail 0.1 --metric rmse,psnr "
          "--diff " +
              path("diff.####.exr") + " " + path("out.####.exr") + " " + path("ref.####.exr"),
          &text);
  EXPECT_EQ(code, 2);
  const nlohmann::json j = nlohmann::json::parse(text);
  ASSERT_EQ(j["frames"].size(), 3u);
  EXPECT_EQ(j["frames"][0]["status"], "ok");
  EXPECT_TRUE(j["frames"][0]["overall"]["psnr"].is_null());  // identical: infinite
  EXPECT_EQ(j["frames"][1]["status"], "fail");
  EXPECT_EQ(j["frames"][2]["status"], "warn");
  EXPECT_FALSE(j["frames"][1]["overall"].contains("ssim"));
  EXPECT_EQ(j["frames"][1]["subimages"][0]["max_error_at"]["channel"], "indirect.G");
  EXPECT_EQ(j["frames"][1]["subimages"][0]["fail_pixels"], 1);
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

// `ssgi compare` against Debian's idiff (OIIO 2.4) on the same pairs and options: the same
// exit code, stdout and stderr, and (for a readable failure) the same numbers line by line.
class IdiffAgreement : public CompareFiles {
 protected:
  void SetUp() override {
    CompareFiles::SetUp();
    const std::string idiff = SSGI_IDIFF_BINARY;
    if (idiff.empty() || !fs::exists(idiff)) GTEST_SKIP() << "idiff (openimageio-tools) not found";
  }

  void expect_same(const std::string& args);

  struct Output {
    int code = -1;
    std::string out, err;
  };

  Output run_tool(const std::string& tool, const std::string& args) {
    const std::string out = path("stdout.txt"), err = path("stderr.txt");
    const int status = std::system((tool + " " + args + " >" + out + " 2>" + err).c_str());
    auto slurp = [](const std::string& file) {
      std::ifstream in(file);
      std::stringstream text;
      text << in.rdbuf();
      return text.str();
    };
    return Output{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  }

  // "  Mean error = 0.0123" -> {"Mean error", 0.0123}, for each such line in order.
  static std::vector<std::pair<std::string, double>> numbers(const std::string& text) {
    std::vector<std::pair<std::string, double>> found;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      for (const char* key : {"Mean error = ", "RMS error = ", "Peak SNR = ", "Max error  = "}) {
        const std::size_t at = line.find(key);
        if (at != std::string::npos)
          found.emplace_back(key, std::strtod(line.c_str() + at + std::strlen(key), nullptr));
      }
    }
    return found;
  }

  // A w x h image of `channels` channels: a smooth ramp plus what `edit` changes.
  std::string image(const std::string& name, int w, int h, int channels,
                    const std::vector<std::tuple<int, int, int, float>>& edits = {}, int x0 = 0,
                    int y0 = 0) {
    const char* names[] = {"R", "G", "B", "A"};
    std::vector<Channel> planes;
    for (int c = 0; c < channels; ++c) {
      std::vector<float> v(static_cast<std::size_t>(w) * h);
      for (int p = 0; p < w * h; ++p) v[p] = 0.1f + 0.05f * c + 0.01f * (p % 7) + 0.002f * p;
      planes.push_back({names[c], v});
    }
    for (const auto& [x, y, c, delta] : edits) planes[c].pixels[y * w + x] += delta;
    return write(name, w, h, {{"", planes}}, x0, y0);
  }
};

// The verdict, numbers and text of `ssgi compare ARGS` and `idiff ARGS`.
void IdiffAgreement::expect_same(const std::string& args) {
  const Output expected = run_tool(SSGI_IDIFF_BINARY, args);
  const Output got = run_tool(std::string(SSGI_BINARY) + " compare", args);
  EXPECT_EQ(got.code, expected.code) << args;
  const auto want = numbers(expected.out), have = numbers(got.out);
  ASSERT_EQ(have.size(), want.size()) << args << "\n" << got.out << "\nidiff:\n" << expected.out;
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(have[i].first, want[i].first) << args;
    if (!std::isfinite(want[i].second))
      EXPECT_EQ(std::to_string(have[i].second), std::to_string(want[i].second)) << args;
    else  // idiff prints 6 significant digits
      EXPECT_NEAR(have[i].second, want[i].second, 1e-5 * std::abs(want[i].second)) << args;
  }
  EXPECT_EQ(got.out, expected.out) << args;
  EXPECT_EQ(got.err, expected.err) << args;
}

TEST_F(IdiffAgreement, ThresholdsAndVerdicts) {
  const std::string ref = image("ref.exr", 8, 6, 3);
  // Differences of 0.02 and 0.004 at a few pixels; and a few pixels 0.2 off.
  const std::string mid =
      image("mid.exr", 8, 6, 3, {{1, 1, 0, 0.02f}, {2, 3, 1, -0.02f}, {5, 4, 2, 0.004f}});
  const std::string far = image(
      "far.exr", 8, 6, 3,
      {{0, 0, 0, 0.2f}, {7, 5, 2, -0.2f}, {3, 3, 1, 0.02f}, {4, 1, 0, 0.004f}, {6, 2, 2, 0.004f}});
  expect_same("-v " + ref + " " + ref);
  expect_same(ref + " " + ref);
  for (const std::string& pair : {mid + " " + ref, ref + " " + far}) {
    for (const char* options :
         {"", "-warn 0.01 -fail 0.05", "-fail 1 -hardfail 0.03",
          "-warn 0.001 -fail 0.01 -failpercent 10",
          "-warn 0.001 -warnpercent 5 -fail 0.01 -failpercent 20 -v",
          "-fail 0.001 -allowfailures 3", "-fail 0.001 -failpercent 50 -hardwarn 0.01",
          "-warnrelative 0.05 -failrelative 0.05 -v"})
      expect_same(std::string(options) + " " + pair);
  }
  expect_same("-q " + far + " " + ref);
}

TEST_F(IdiffAgreement, SizesChannelCountsAndDataWindows) {
  const std::string ref = image("ref.exr", 8, 6, 3);
  const std::string wide = image("wide.exr", 10, 6, 3);
  const std::string rgba = image("rgba.exr", 8, 6, 4);
  const std::string moved = image("moved.exr", 8, 6, 3, {}, 2, 1);
  for (const std::string& pair : {wide + " " + ref, ref + " " + rgba, moved + " " + ref}) {
    expect_same(pair);
    expect_same("-fail 1 -v " + pair);
  }
}

TEST_F(IdiffAgreement, NonFiniteValues) {
  const std::string ref = image("ref.exr", 8, 6, 3);
  const std::string nan1 = image("nan1.exr", 8, 6, 3, {{3, 2, 1, kNaN}});
  const std::string nan2 = image("nan2.exr", 8, 6, 3, {{3, 2, 1, kNaN}, {4, 4, 0, kInfF}});
  expect_same("-v " + nan1 + " " + ref);  // one NaN: an infinite max error, yet PASS
  expect_same("-v " + nan2 + " " + ref);
  expect_same("-v " + nan1 + " " + nan1);
  expect_same("-q " + ref + " " + nan2);
}

TEST_F(IdiffAgreement, Subimages) {
  // Two parts: the first equal, the second 0.02 off at one pixel.
  auto parts = [&](const std::string& name, float delta) {
    std::vector<float> v(48, 0.25f), d = v;
    d[13] += delta;
    return write(
        name, 8, 6,
        {{"one", {{"R", v}, {"G", v}, {"B", v}}}, {"two", {{"R", d}, {"G", v}, {"B", v}}}});
  };
  const std::string a = parts("parts_a.exr", 0.0f), b = parts("parts_b.exr", 0.02f);
  const std::string single = image("single.exr", 8, 6, 3);
  for (const char* options : {"", "-a", "-a -v -fail 0.01 -failpercent 10", "-q -a"})
    expect_same(std::string(options) + " " + a + " " + b);
  for (const char* options : {"", "-a", "-q -a"})
    expect_same(std::string(options) + " " + a + " " + single);
}

}  // namespace
}  // namespace ssgi
