// idiff's numbers and verdict: OpenImageIO 2.4's ImageBufAlgo::compare and the rules of its
// idiff tool, sample by sample in the same float and double arithmetic and the same order, so
// that `ssgi compare` prints what idiff prints.
#include <algorithm>
#include <cmath>
#include <limits>

#include "ssgi/compare.h"

namespace ssgi {
namespace {

// ImageBufAlgo::compare sums the errors of 4096 pixels at a time before adding them to the
// total (against cancellation); the same batches give the same last bits.
constexpr std::size_t kBatchPixels = 4096;

Box2i union_of(const Box2i& a, const Box2i& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return {std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
}

// The per-pixel state that compare_value() carries.
struct PixelState {
  bool warned = false, failed = false;
};

// OIIO 2.4's compare_value(), line for line (float differences, a float running peak, the
// '!(a <= b)' tests that count a NaN difference as over a threshold).
void compare_value(float aval, float bval, int x, int y, int c, const IdiffThresholds& t,
                   IdiffStats* result, float* maxval, double* batch_error, double* batch_sqr_error,
                   PixelState* pixel) {
  if (!std::isfinite(aval) || !std::isfinite(bval)) {
    // NaN matches NaN and an infinity matches an infinity (of either sign).
    if (std::isnan(aval) == std::isnan(bval) && std::isinf(aval) == std::isinf(bval)) return;
    // The first non-finite mismatch sets the max error to inf and is not counted further;
    // once the max error is not finite, the next ones go through the finite path below.
    if (std::isfinite(result->max_error)) {
      result->max_error = std::numeric_limits<float>::infinity();
      result->max_x = x;
      result->max_y = y;
      result->max_channel = c;
      return;
    }
  }
  const float aabs = std::abs(aval), babs = std::abs(bval);
  const float meanabs = static_cast<float>(aabs * (1.0 - 0.5) + babs * 0.5);  // OIIO's lerp
  const float maxabs = std::max(aabs, babs);
  *maxval = std::max(*maxval, maxabs);
  const double f = std::abs(aval - bval);
  const double rel = meanabs > 0.0 ? f / meanabs : 0.0;
  *batch_error += f;
  *batch_sqr_error += f * f;
  if (!(f <= result->max_error)) {
    result->max_error = f;
    result->max_x = x;
    result->max_y = y;
    result->max_channel = c;
  }
  if (!pixel->warned && !(f <= t.warn) && !(rel <= t.warn_relative)) {
    ++result->warn_pixels;
    pixel->warned = true;
  }
  if (!pixel->failed && !(f <= t.fail) && !(rel <= t.fail_relative)) {
    ++result->fail_pixels;
    pixel->failed = true;
  }
}

}  // namespace

IdiffStats idiff_compare(const WindowedImage& a, const WindowedImage& b,
                         const IdiffThresholds& thresholds) {
  const Box2i roi = union_of(a.window, b.window);
  const int channels = std::max(a.pixels.channels(), b.pixels.channels());
  const std::size_t npels =
      roi.empty() ? 0
                  : static_cast<std::size_t>(roi.width()) * static_cast<std::size_t>(roi.height());
  const double nvals = static_cast<double>(npels) * channels;

  IdiffStats result;
  // PSNR's peak: 1 for images in [0, 1], else the largest |value| of either image.
  float maxval = 1.0f;
  double total_error = 0.0, total_sqr_error = 0.0;
  double batch_error = 0.0, batch_sqr_error = 0.0;
  std::size_t in_batch = 0;
  for (int y = roi.y0; y < roi.y1; ++y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      PixelState pixel;
      for (int c = 0; c < channels; ++c)
        compare_value(a.sample(x, y, c), b.sample(x, y, c), x, y, c, thresholds, &result, &maxval,
                      &batch_error, &batch_sqr_error, &pixel);
      if (++in_batch == kBatchPixels) {
        total_error += batch_error;
        total_sqr_error += batch_sqr_error;
        batch_error = batch_sqr_error = 0.0;
        in_batch = 0;
      }
    }
  }
  total_error += batch_error;
  total_sqr_error += batch_sqr_error;
  // An empty union divides 0 by 0, as OIIO does.
  result.mean_error = total_error / nvals;
  result.rms_error = std::sqrt(total_sqr_error / nvals);
  result.psnr = 20.0 * std::log10(maxval / result.rms_error);
  return result;
}

CompareStatus idiff_status(const IdiffStats& stats, std::size_t pixels,
                           const IdiffThresholds& thresholds, CompareStatus so_far) {
  const double npels = static_cast<double>(pixels);
  // A negative -allowfailures becomes a huge unsigned count in idiff: everything passes.
  if (stats.fail_pixels <= static_cast<std::size_t>(thresholds.allow_failures)) return so_far;
  if (stats.fail_pixels > thresholds.fail_percent / 100.0 * npels ||
      stats.max_error > thresholds.hard_fail)
    return CompareStatus::kFail;
  if (stats.warn_pixels > thresholds.warn_percent / 100.0 * npels ||
      stats.max_error > thresholds.hard_warn)
    return so_far == CompareStatus::kFail ? so_far : CompareStatus::kWarn;
  return so_far;
}

}  // namespace ssgi
