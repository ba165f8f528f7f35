// Comparing two outputs: ssgi's error metrics (RMSE, relMSE, PSNR, SSIM) per layer of two EXR
// files' channels, as `ssgi compare --metric` reports them.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace ssgi {

// The error metrics, in report order. Definitions are in the man page (ssgi compare).
enum class Metric : int { kRmse, kRelRmse, kRelMse, kPsnr, kSsim };
constexpr int kMetricCount = 5;

// "rmse", "relrmse", "relmse", "psnr", "ssim".
const char* metric_name(Metric metric);

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
  bool compute_ssim = true;  // SSIM costs the most; skip it when it is not reported
  // Without a background mask, leave out of a layer's metrics the pixels where all its
  // reference channels are exactly 0 (background of a GI layer, which both sides get right).
  bool exclude_zero_reference = true;
};

// Everything one comparison measures.
struct CompareResult {
  std::vector<LayerStats> layers;
  LayerStats overall;  // all layers' samples pooled; SSIM is the pixel-weighted layer mean
};

// Which channels of two files a layer compares.
struct LayerChannels {
  std::string name;
  std::vector<std::string> a, b;  // full channel names, pairwise
  bool rgb = false;
};

// How to compare two EXR files.
struct FileCompareOptions {
  // `ssgi compare --channels` items: NAME or A_NAME=B_NAME, a name a channel or a layer whose
  // R, G, B are compared; empty: every layer with R, G, B in both files (the root layer too).
  std::vector<std::string> channels;
  // The reference's depth channel that marks background; empty: `Z` or a `*depth.Z` channel
  // when the reference has one, else CompareOptions::exclude_zero_reference.
  std::string depth_channel;
  bool all_pixels = false;  // no background: every pixel counts in the metrics
  CompareOptions compare;
};

// A file comparison: the metrics and what they were computed on.
struct FileCompareResult {
  CompareResult result;
  std::vector<LayerChannels> layers;
  std::vector<std::string> plane_names;  // a's channel name of each plane
  std::string depth_channel;             // the reference channel used for background, if any
};

// Reads the selected channels of `a_path` and the reference `b_path` by name and computes
// ssgi's metrics on them. Throws Error(kIO) naming a file that cannot be read, Error(kInput)
// for a missing channel or data windows that differ.
FileCompareResult compare_files(const std::string& a_path, const std::string& b_path,
                                const FileCompareOptions& options);

}  // namespace ssgi
