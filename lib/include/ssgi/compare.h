// Image comparison for regression tests and accuracy measurements: error metrics on planar
// float images, idiff-style pass/warn/fail thresholds, and the same on two EXR files' channels
// selected by name (the library side of `ssgi compare`).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ssgi/image.h"
#include "ssgi/layout.h"

namespace ssgi {

// The error metrics, in report order. Definitions are in the man page (ssgi compare).
enum class Metric : int { kRmse, kRelRmse, kRelMse, kPsnr, kSsim };
constexpr int kMetricCount = 5;

// "rmse", "relrmse", "relmse", "psnr", "ssim".
const char* metric_name(Metric metric);
// True for PSNR and SSIM, where a larger value is a closer match.
bool metric_higher_is_better(Metric metric);
// Parses a comma list of metric names ("all" for every metric), in the order given without
// repeats. Throws Error(kUsage) on an unknown or missing name.
std::vector<Metric> parse_metric_list(const std::string& list);

// relMSE = mean((a - b)^2 / (b^2 + epsilon)): epsilon keeps near-black reference pixels from
// dominating (the value used by Rousselle et al. and most denoising papers).
constexpr double kRelMseEpsilon = 0.01;
// A reference depth at or beyond this (or not finite) marks a background pixel: Blender writes
// 1e10, Arnold AI_BIG (1e12), others inf.
constexpr double kBackgroundDepth = 1e9;

// idiff's thresholds on the per-pixel absolute difference (the largest over the compared
// channels). The defaults are idiff's: any difference above 1e-6 fails.
struct Thresholds {
  double warn = 1e-6;         // a pixel "warns" when its difference exceeds this
  double warn_percent = 0.0;  // WARN when more than this % of pixels warn
  double fail = 1e-6;         // a pixel "fails" when its difference exceeds this
  double fail_percent = 0.0;  // FAIL when more than this % of pixels fail
  double hard_fail = std::numeric_limits<double>::infinity();  // FAIL when any pixel exceeds
};

// Outcome of a comparison; the numeric values are `ssgi compare`'s exit codes.
enum class CompareStatus : int { kOk = 0, kWarn = 1, kFail = 2 };
// "ok", "warn", "fail".
const char* status_name(CompareStatus status);

// Per-pixel difference counts over every pixel of the image (background included, as idiff).
struct PixelDiffStats {
  std::size_t pixels = 0;
  std::size_t warn_pixels = 0;  // pixels whose difference exceeds Thresholds::warn
  std::size_t fail_pixels = 0;  // pixels whose difference exceeds Thresholds::fail
  double max_error = 0.0;       // the largest difference; inf when only one side is not finite
  int max_x = -1, max_y = -1;   // where it is (data-window pixel), -1 when all equal
  int max_plane = -1;           // and in which plane
};

// Applies idiff's rules: FAIL when more than fail_percent % of pixels fail or any pixel exceeds
// hard_fail; otherwise WARN when more than warn_percent % of pixels warn; otherwise OK.
CompareStatus evaluate_thresholds(const PixelDiffStats& diff, const Thresholds& thresholds);

// A group of planes reported together (an EXR layer such as `indirect`).
struct CompareLayer {
  std::string name;
  std::vector<int> planes;  // plane indices, the same in both images
  bool rgb = false;         // planes are R, G, B: SSIM uses their Rec.709 luminance
};

// The metrics of one layer, or of all layers together.
struct LayerStats {
  std::string name;
  // Indexed by Metric; empty when undefined (no foreground samples, a reference mean or peak
  // of 0) or not computed. PSNR is +inf for identical images.
  std::array<std::optional<double>, kMetricCount> metrics;
  std::size_t foreground_pixels = 0;  // pixels the metrics cover
  std::size_t samples = 0;            // (pixel, channel) samples in RMSE, relRMSE, relMSE, PSNR
  std::size_t nonfinite_samples = 0;  // foreground samples left out: a or b is inf or NaN
  double reference_mean = 0.0;        // mean of b over the samples
  double reference_peak = 0.0;        // max of b over the samples: PSNR's peak
  double max_error = 0.0;             // largest |a - b| over every pixel of the layer

  const std::optional<double>& metric(Metric m) const { return metrics[static_cast<int>(m)]; }
};

// How to compare.
struct CompareOptions {
  Thresholds thresholds;
  bool compute_ssim = true;  // SSIM costs ~20x the rest; skip it when it is not reported
  // Without a background mask, leave out of a layer's metrics the pixels where all its
  // reference channels are exactly 0 (background of a GI layer, which both sides get right).
  bool exclude_zero_reference = true;
};

// Everything one comparison measures.
struct CompareResult {
  std::vector<LayerStats> layers;
  LayerStats overall;  // all layers' samples pooled; SSIM is the pixel-weighted layer mean
  PixelDiffStats pixels;
  CompareStatus status = CompareStatus::kOk;
};

// Compares `a` against the reference `b` (same size and plane count). `background`, when not
// empty, holds one byte per pixel, nonzero for pixels left out of every layer's metrics (but
// not out of the thresholds).
CompareResult compare_images(const Image& a, const Image& b,
                             const std::vector<CompareLayer>& layers, const CompareOptions& options,
                             const std::vector<std::uint8_t>& background = {});

// |a - b| * scale per sample (same sizes): 0 where both are the same infinity or both NaN, +inf
// where only one side is not finite.
Image difference_image(const Image& a, const Image& b, float scale = 1.0f);

// The background mask of a reference depth plane: 1 where depth is not finite or
// |depth| >= kBackgroundDepth.
std::vector<std::uint8_t> background_from_depth(const float* depth, std::size_t pixels);

// One metric across a sequence.
struct MetricSummary {
  std::optional<double> mean;   // over the frames where it is defined
  std::optional<double> worst;  // largest error (smallest PSNR, SSIM)
  int worst_index = -1;         // the frame that has it, as an index into the results
};

// One layer (by name) across a sequence.
struct LayerSummary {
  std::string name;
  std::array<MetricSummary, kMetricCount> metrics;
};

// A sequence's comparisons summed up.
struct SequenceSummary {
  std::vector<LayerSummary> layers;  // in order of first appearance
  LayerSummary overall;
  std::array<int, 3> status_counts{};  // frames per CompareStatus
  CompareStatus status = CompareStatus::kOk;
  int worst_index = -1;  // the worst status, ties broken by the largest overall RMSE
};

// Summarises per-frame results (an empty list gives an empty summary).
SequenceSummary summarize_frames(const std::vector<CompareResult>& frames);

// Which channels of two files a layer compares.
struct LayerChannels {
  std::string name;
  std::vector<std::string> a, b;  // full channel names, pairwise
  bool rgb = false;
};

// Resolves `--channels` items against two files' channels. An item is NAME or A_NAME=B_NAME;
// a name is a channel, or a layer whose R, G, B channels are compared. Channels are grouped
// into layers by their prefix before the last '.'. With no items: every layer that has R, G, B
// in both files (the root layer too). Multi-part channels without a layer of their own are
// named `<part>.<channel>`. Throws Error(kUsage) on a malformed item and Error(kInput) naming
// the file that lacks a channel, or when no RGB layer is common.
std::vector<LayerChannels> select_layers(const std::string& a_path, const FileChannels& a,
                                         const std::string& b_path, const FileChannels& b,
                                         const std::vector<std::string>& items);

// How to compare two EXR files.
struct FileCompareOptions {
  std::vector<std::string> channels;  // select_layers() items; empty: the common RGB layers
  // The reference's depth channel that marks background; empty: `Z` or a `*depth.Z` channel
  // when the reference has one, else CompareOptions::exclude_zero_reference.
  std::string depth_channel;
  bool all_pixels = false;  // no background: every pixel counts in the metrics
  CompareOptions compare;
  std::string diff_path;  // write |a - b| * diff_scale of the compared channels here
  float diff_scale = 1.0f;
};

// A file comparison: the metrics and what they were computed on.
struct FileCompareResult {
  CompareResult result;  // max_x, max_y in display coordinates (the data window's origin added)
  std::vector<LayerChannels> layers;
  std::vector<std::string> plane_names;  // a's channel name of each plane (max_plane indexes it)
  std::string depth_channel;             // the reference channel used for background, if any
};

// Reads the selected channels of `a_path` and the reference `b_path` by name and compares
// them; writes the difference image when asked (atomically: a temporary file, then rename).
// Throws Error(kIO) naming a file that cannot be read or written, Error(kInput) for a
// missing channel or data windows that differ.
FileCompareResult compare_files(const std::string& a_path, const std::string& b_path,
                                const FileCompareOptions& options);

}  // namespace ssgi
