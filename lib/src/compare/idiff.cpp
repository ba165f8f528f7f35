// idiff's numbers and verdict: OpenImageIO's own ImageBufAlgo::compare, which idiff calls, and
// the rules of idiff's verdict.
#include "compare/idiff.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace ssgi {
namespace {

Box2i union_of(const Box2i& a, const Box2i& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return {std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
}

// The image as OIIO reads it: interleaved floats over its data window, with `channels` channels
// (those past its own are 0, as idiff reads a file with fewer channels), in `pixels`, which the
// returned buffer wraps without a copy of its own.
OIIO::ImageBuf image_buf(const WindowedImage& image, int channels, std::vector<float>* pixels) {
  OIIO::ImageSpec spec(image.window.width(), image.window.height(), channels,
                       OIIO::TypeDesc::FLOAT);
  spec.x = image.window.x0;
  spec.y = image.window.y0;
  pixels->assign(spec.image_pixels() * static_cast<std::size_t>(channels), 0.0f);
  const int own = image.pixels.channels();
  const std::size_t n = image.pixels.plane_size();
  for (int c = 0; c < std::min(own, channels); ++c) {
    const float* plane = image.pixels.plane(c);
    for (std::size_t p = 0; p < n; ++p) (*pixels)[p * channels + c] = plane[p];
  }
  return OIIO::ImageBuf(spec, pixels->data());
}

}  // namespace

const char* status_name(CompareStatus status) {
  switch (status) {
    case CompareStatus::kOk:
      return "ok";
    case CompareStatus::kWarn:
      return "warn";
    case CompareStatus::kFail:
      return "fail";
  }
  return "?";
}

IdiffStats idiff_compare(const WindowedImage& a, const WindowedImage& b,
                         const IdiffThresholds& thresholds) {
  const Box2i roi = union_of(a.window, b.window);
  IdiffStats result;
  if (roi.empty()) {
    // An empty union divides 0 by 0, as OIIO does.
    const double zero = 0.0;
    result.mean_error = zero / zero;
    result.rms_error = std::sqrt(result.mean_error);
    result.psnr = 20.0 * std::log10(1.0 / result.rms_error);
    return result;
  }
  const int channels = std::max(a.pixels.channels(), b.pixels.channels());
  std::vector<float> a_pixels, b_pixels;
  const OIIO::ImageBuf A = image_buf(a, channels, &a_pixels), B = image_buf(b, channels, &b_pixels);
  const OIIO::ROI region(roi.x0, roi.x1, roi.y0, roi.y1, 0, 1, 0, channels);
  const OIIO::ImageBufAlgo::CompareResults r =
      OIIO::ImageBufAlgo::compare(A, B, thresholds.fail, thresholds.warn, thresholds.fail_relative,
                                  thresholds.warn_relative, region);
  result.mean_error = r.meanerror;
  result.rms_error = r.rms_error;
  result.psnr = r.PSNR;
  result.max_error = r.maxerror;
  result.max_x = r.maxx;
  result.max_y = r.maxy;
  result.max_channel = r.maxc;
  result.warn_pixels = static_cast<std::size_t>(r.nwarn);
  result.fail_pixels = static_cast<std::size_t>(r.nfail);
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
