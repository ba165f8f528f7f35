// Image comparison for regression tests and accuracy measurements: OIIO idiff's numbers and
// verdicts, and ssgi's error metrics on planar float images, each also on two EXR files'
// channels (the library side of `ssgi compare`).
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

// Outcome of a comparison; the numeric values are `ssgi compare`'s exit codes.
enum class CompareStatus : int { kOk = 0, kWarn = 1, kFail = 2 };
// "ok", "warn", "fail".
const char* status_name(CompareStatus status);

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
  bool compute_ssim = true;  // SSIM costs far more than the rest; skip it when not reported
  // Without a background mask, leave out of a layer's metrics the pixels where all its
  // reference channels are exactly 0 (background of a GI layer, which both sides get right).
  bool exclude_zero_reference = true;
};

// Everything one comparison measures.
struct CompareResult {
  std::vector<LayerStats> layers;
  LayerStats overall;  // all layers' samples pooled; SSIM is the pixel-weighted layer mean
};

// Compares `a` against the reference `b` (same size and plane count). `background`, when not
// empty, holds one byte per pixel, nonzero for pixels left out of every layer's metrics.
CompareResult compare_images(const Image& a, const Image& b,
                             const std::vector<CompareLayer>& layers, const CompareOptions& options,
                             const std::vector<std::uint8_t>& background = {});

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

// A sequence's metrics summed up.
struct SequenceSummary {
  std::vector<LayerSummary> layers;  // in order of first appearance
  LayerSummary overall;
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

// idiff (OpenImageIO 2.4's `idiff` and ImageBufAlgo::compare), reproduced so that `ssgi
// compare` gives its numbers and statuses: every channel by index (the union of both channel
// counts, a missing channel read as 0) over the union of both data windows (outside a window,
// black). The per-sample rules, NaN and infinity quirks included, are those of OIIO 2.4.

// idiff's thresholds. They are floats because idiff parses them as floats: `-warn 0.01` is
// 0.01f, and a difference of exactly 0.01 (a double) is over it.
struct IdiffThresholds {
  float fail = 1e-6f;          // a pixel fails when a channel differs by more (and rel. below)
  float fail_relative = 0.0f;  // ... and |a - b| / mean(|a|, |b|) exceeds this
  float fail_percent = 0.0f;   // FAIL when more than this % of A's pixels fail
  float hard_fail = std::numeric_limits<float>::infinity();  // FAIL when the max error exceeds
  int allow_failures = 0;  // PASS whatever else when at most this many pixels fail
  float warn = 1e-6f;
  float warn_relative = 0.0f;
  float warn_percent = 0.0f;
  float hard_warn = std::numeric_limits<float>::infinity();
};

// An image as idiff sees one subimage: float samples in a data window.
struct WindowedImage {
  Box2i window;  // the data window, in pixel coordinates
  Image pixels;  // window-sized planes
  std::vector<std::string> channel_names;

  // Channel c at (x, y); 0 outside the data window or past the last channel (OIIO's black).
  float sample(int x, int y, int c) const {
    if (c >= pixels.channels() || !window.contains(x, y)) return 0.0f;
    return pixels.at(c, x - window.x0, y - window.y0);
  }
};

// ImageBufAlgo::compare's results.
struct IdiffStats {
  double mean_error = 0.0;  // sum |a - b| / (pixels x channels) of the union; inf or NaN when
  double rms_error = 0.0;   // ... a non-finite difference gets into the sums
  double psnr = 0.0;        // 20 log10(peak / rms), peak = max(1, largest |a|, |b|)
  double max_error = 0.0;   // inf for a non-finite value against a different one
  int max_x = 0, max_y = 0, max_channel = 0;  // where the max error is; meaningful when it is not 0
  std::size_t warn_pixels = 0, fail_pixels = 0;
};

// Compares two images as ImageBufAlgo::compare(a, b, fail, warn, fail_relative,
// warn_relative) does.
IdiffStats idiff_compare(const WindowedImage& a, const WindowedImage& b,
                         const IdiffThresholds& thresholds);

// idiff's verdict after one more subimage, from the verdict so far: when at most
// allow_failures pixels fail, nothing changes (so without a failing pixel there is no
// warning and no hard failure either); else FAIL when more than fail_percent % of `pixels`
// fail or the max error exceeds hard_fail; else WARN when more than warn_percent % warn or the
// max error exceeds hard_warn. `pixels` is A's pixel count (at least 1).
CompareStatus idiff_status(const IdiffStats& stats, std::size_t pixels,
                           const IdiffThresholds& thresholds, CompareStatus so_far);

// How idiff compares two files.
struct IdiffOptions {
  IdiffThresholds thresholds;
  bool all_subimages = false;  // -a: every subimage (part), else the first
  // select_layers() items: compare these channels (B's paired with A's by name, from any part)
  // as one image named as in A, instead of each subimage's channels by index.
  std::vector<std::string> channels;
  std::string diff_path;  // -o: write A - B (of the first subimage compared) here
  bool diff_abs = false;  // -abs: |A - B|
  float diff_scale = 1.0f;
  bool diff_only_if_different = false;  // -od: only when the max error is not 0
};

// One subimage as idiff reports it.
struct IdiffSubimage {
  int subimage = 0;
  int width = 0, height = 0, channels = 0;  // A's
  std::size_t pixels = 1;                   // A's pixel count, the base of the percentages
  IdiffStats stats;
  CompareStatus status = CompareStatus::kOk;  // the file's verdict after this subimage
  std::string max_channel_name;               // A's name of stats.max_channel, else B's
  std::vector<float> a_values, b_values;      // every channel at (max_x, max_y), as read
};

// A file comparison as idiff does it.
struct IdiffFileResult {
  std::vector<IdiffSubimage> subimages;       // those compared, in order
  int a_subimages = 1, b_subimages = 1;       // in the files (1 with IdiffOptions::channels)
  CompareStatus status = CompareStatus::kOk;  // FAIL too when -a meets unequal subimage counts
  bool diff_written = false;
};

// Compares `a_path` with `b_path` as idiff does and writes the difference image when asked
// (atomically). Throws Error(kIO) naming a file that cannot be read or written, Error(kInput)
// for deep data or a channel --channels names that is missing, Error(kUsage) for channels
// together with all_subimages.
IdiffFileResult idiff_files(const std::string& a_path, const std::string& b_path,
                            const IdiffOptions& options);

}  // namespace ssgi
