// The comparison `ssgi compare` makes as OpenImageIO's idiff does: its numbers, thresholds and
// verdicts.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "ssgi/image.h"

namespace ssgi {

// Outcome of a comparison; the numeric values are `ssgi compare`'s exit codes.
enum class CompareStatus : int { kOk = 0, kWarn = 1, kFail = 2 };
// "ok", "warn", "fail".
const char* status_name(CompareStatus status);

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

}  // namespace ssgi
