// ssgi's error metrics between planar float images: RMSE, relRMSE, relMSE, PSNR, SSIM over
// the foreground pixels of each layer.
#include "compare/compare.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "throw.h"

namespace ssgi {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Wang, Bovik, Sheikh, Simoncelli 2004: an 11x11 Gaussian window of sigma 1.5, K1 = 0.01 and
// K2 = 0.03.
constexpr int kSsimRadius = 5;
constexpr double kSsimSigma = 1.5;
constexpr double kSsimK1 = 0.01;
constexpr double kSsimK2 = 0.03;

// Rec.709 / sRGB luminance weights.
constexpr double kLumaR = 0.2126, kLumaG = 0.7152, kLumaB = 0.0722;

// |a - b|, with non-finite values made comparable: equal infinities or two NaNs do not differ,
// a non-finite value against anything else differs infinitely.
double sample_difference(float a, float b) {
  if (std::isfinite(a) && std::isfinite(b)) return std::abs(static_cast<double>(a) - b);
  if (a == b || (std::isnan(a) && std::isnan(b))) return 0.0;
  return kInf;
}

// Sums from which a layer's (or all layers') metrics follow.
struct ErrorSums {
  double squared = 0.0;   // sum (a - b)^2
  double relative = 0.0;  // sum (a - b)^2 / (b^2 + eps)
  double reference = 0.0;
  double peak = -kInf;
  std::size_t samples = 0;
  std::size_t nonfinite = 0;

  void add(const ErrorSums& o) {
    squared += o.squared;
    relative += o.relative;
    reference += o.reference;
    peak = std::max(peak, o.peak);
    samples += o.samples;
    nonfinite += o.nonfinite;
  }
};

// Fills everything but SSIM from `sums`.
void set_error_metrics(const ErrorSums& sums, LayerStats* stats) {
  stats->samples = sums.samples;
  stats->nonfinite_samples = sums.nonfinite;
  if (sums.samples == 0) return;
  const double n = static_cast<double>(sums.samples);
  const double mse = sums.squared / n;
  const double rmse = std::sqrt(mse);
  stats->reference_mean = sums.reference / n;
  stats->reference_peak = sums.peak;
  stats->metrics[static_cast<int>(Metric::kRmse)] = rmse;
  if (stats->reference_mean > 0.0)
    stats->metrics[static_cast<int>(Metric::kRelRmse)] = rmse / stats->reference_mean;
  stats->metrics[static_cast<int>(Metric::kRelMse)] = sums.relative / n;
  if (sums.peak > 0.0) {
    stats->metrics[static_cast<int>(Metric::kPsnr)] =
        mse == 0.0 ? kInf : 10.0 * std::log10(sums.peak * sums.peak / mse);
  }
}

// The signal SSIM looks at: Rec.709 luminance of an RGB layer, else the mean of its planes.
// Non-finite samples count as 0, so that one NaN does not spread over its whole window.
std::vector<float> ssim_signal(const Image& image, const CompareLayer& layer) {
  std::vector<float> signal(image.plane_size(), 0.0f);
  const std::size_t nplanes = layer.planes.size();
  for (std::size_t i = 0; i < nplanes; ++i) {
    const double weight = layer.rgb ? (i == 0 ? kLumaR : i == 1 ? kLumaG : kLumaB) : 1.0 / nplanes;
    const float* plane = image.plane(layer.planes[i]);
    for (std::size_t p = 0; p < signal.size(); ++p) {
      if (std::isfinite(plane[p])) signal[p] += static_cast<float>(weight * plane[p]);
    }
  }
  return signal;
}

// Mean SSIM over the foreground pixels. Window statistics near the border use the part of the
// window inside the image, renormalised, so that every pixel (even of a 1x1 image) has a value.
// The five windowed moments are filtered separably; a ring of 11 horizontally filtered rows
// keeps memory at O(width).
double mean_ssim(const std::vector<float>& a, const std::vector<float>& b, int width, int height,
                 double peak, const std::vector<std::uint8_t>& foreground) {
  const double c1 = (kSsimK1 * peak) * (kSsimK1 * peak);
  const double c2 = (kSsimK2 * peak) * (kSsimK2 * peak);
  constexpr int kTaps = 2 * kSsimRadius + 1;
  double gauss[kTaps];
  for (int k = -kSsimRadius; k <= kSsimRadius; ++k)
    gauss[k + kSsimRadius] = std::exp(-(k * k) / (2.0 * kSsimSigma * kSsimSigma));

  constexpr int kMoments = 5;  // a, b, a^2, b^2, ab
  const std::size_t w = static_cast<std::size_t>(width);
  std::vector<double> ring(static_cast<std::size_t>(kTaps) * kMoments * w);
  auto ring_row = [&](int y) { return ring.data() + (y % kTaps) * kMoments * w; };
  auto filter_row = [&](int y) {
    double* out = ring_row(y);
    const float* ra = a.data() + y * w;
    const float* rb = b.data() + y * w;
    for (int x = 0; x < width; ++x) {
      double m[kMoments] = {}, wsum = 0.0;
      for (int k = std::max(-kSsimRadius, -x); k <= std::min(kSsimRadius, width - 1 - x); ++k) {
        const double g = gauss[k + kSsimRadius], va = ra[x + k], vb = rb[x + k];
        m[0] += g * va;
        m[1] += g * vb;
        m[2] += g * va * va;
        m[3] += g * vb * vb;
        m[4] += g * va * vb;
        wsum += g;
      }
      for (int q = 0; q < kMoments; ++q) out[q * w + x] = m[q] / wsum;
    }
  };

  double sum = 0.0;
  std::size_t count = 0;
  int filtered = 0;  // rows [0, filtered) have been filtered horizontally
  for (int y = 0; y < height; ++y) {
    const int y0 = std::max(0, y - kSsimRadius), y1 = std::min(height - 1, y + kSsimRadius);
    for (; filtered <= y1; ++filtered) filter_row(filtered);
    for (int x = 0; x < width; ++x) {
      if (!foreground.empty() && !foreground[y * w + x]) continue;
      double m[kMoments] = {}, wsum = 0.0;
      for (int yy = y0; yy <= y1; ++yy) {
        const double g = gauss[yy - y + kSsimRadius];
        const double* row = ring_row(yy);
        for (int q = 0; q < kMoments; ++q) m[q] += g * row[q * w + x];
        wsum += g;
      }
      for (double& v : m) v /= wsum;
      // E[x^2] - E[x]^2 can round below 0 in flat regions; a variance cannot.
      const double var_a = std::max(0.0, m[2] - m[0] * m[0]);
      const double var_b = std::max(0.0, m[3] - m[1] * m[1]);
      const double cov = m[4] - m[0] * m[1];
      sum += ((2.0 * m[0] * m[1] + c1) * (2.0 * cov + c2)) /
             ((m[0] * m[0] + m[1] * m[1] + c1) * (var_a + var_b + c2));
      ++count;
    }
  }
  return count ? sum / count : 0.0;
}

}  // namespace

const char* metric_name(Metric metric) {
  switch (metric) {
    case Metric::kRmse:
      return "rmse";
    case Metric::kRelRmse:
      return "relrmse";
    case Metric::kRelMse:
      return "relmse";
    case Metric::kPsnr:
      return "psnr";
    case Metric::kSsim:
      return "ssim";
  }
  return "?";
}

bool metric_higher_is_better(Metric metric) {
  return metric == Metric::kPsnr || metric == Metric::kSsim;
}

std::vector<std::uint8_t> background_from_depth(const float* depth, std::size_t pixels) {
  std::vector<std::uint8_t> background(pixels);
  for (std::size_t p = 0; p < pixels; ++p)
    background[p] = !(std::abs(depth[p]) < kBackgroundDepth);  // NaN is background too
  return background;
}

CompareResult compare_images(const Image& a, const Image& b,
                             const std::vector<CompareLayer>& layers, const CompareOptions& options,
                             const std::vector<std::uint8_t>& background) {
  if (a.width() != b.width() || a.height() != b.height() || a.channels() != b.channels())
    throw_input({}, "images differ in size or channel count");
  const std::size_t npix = a.plane_size();
  if (!background.empty() && background.size() != npix)
    throw_input({}, "background mask differs in size from the images");

  CompareResult result;
  ErrorSums all_sums;
  double ssim_weighted = 0.0;
  std::size_t ssim_pixels = 0;
  std::vector<std::uint8_t> foreground(npix), in_any_layer(npix, 0);

  for (const CompareLayer& layer : layers) {
    LayerStats stats;
    stats.name = layer.name;
    for (std::size_t p = 0; p < npix; ++p) {
      bool fg = true;
      if (!background.empty()) {
        fg = !background[p];
      } else if (options.exclude_zero_reference) {
        fg = false;
        for (int c : layer.planes) fg = fg || b.plane(c)[p] != 0.0f;
      }
      foreground[p] = fg;
      in_any_layer[p] |= fg;
      stats.foreground_pixels += fg;
    }

    ErrorSums sums;
    for (int c : layer.planes) {
      const float* pa = a.plane(c);
      const float* pb = b.plane(c);
      for (std::size_t p = 0; p < npix; ++p) {
        const double diff = sample_difference(pa[p], pb[p]);
        stats.max_error = std::max(stats.max_error, diff);
        if (!foreground[p]) continue;
        if (!std::isfinite(pa[p]) || !std::isfinite(pb[p])) {
          ++sums.nonfinite;
          continue;
        }
        const double va = pa[p], vb = pb[p];
        sums.squared += (va - vb) * (va - vb);
        sums.relative += (va - vb) * (va - vb) / (vb * vb + kRelMseEpsilon);
        sums.reference += vb;
        sums.peak = std::max(sums.peak, vb);
        ++sums.samples;
      }
    }
    set_error_metrics(sums, &stats);
    all_sums.add(sums);

    if (options.compute_ssim && stats.foreground_pixels > 0 && !layer.planes.empty()) {
      // L, the dynamic range in SSIM's constants, is the reference peak (as for PSNR); a
      // reference without positive values falls back to 1 so that the constants stay positive.
      const double peak = stats.reference_peak > 0.0 ? stats.reference_peak : 1.0;
      const double ssim = mean_ssim(ssim_signal(a, layer), ssim_signal(b, layer), a.width(),
                                    a.height(), peak, foreground);
      stats.metrics[static_cast<int>(Metric::kSsim)] = ssim;
      ssim_weighted += ssim * stats.foreground_pixels;
      ssim_pixels += stats.foreground_pixels;
    }
    result.overall.max_error = std::max(result.overall.max_error, stats.max_error);
    result.layers.push_back(std::move(stats));
  }

  result.overall.name = "all";
  result.overall.foreground_pixels =
      static_cast<std::size_t>(std::count(in_any_layer.begin(), in_any_layer.end(), 1));
  set_error_metrics(all_sums, &result.overall);
  if (ssim_pixels > 0)
    result.overall.metrics[static_cast<int>(Metric::kSsim)] = ssim_weighted / ssim_pixels;
  return result;
}

SequenceSummary summarize_frames(const std::vector<CompareResult>& frames) {
  SequenceSummary summary;
  summary.overall.name = "all";
  auto summarize_layer = [&](LayerSummary* out, auto&& stats_of) {
    for (int m = 0; m < kMetricCount; ++m) {
      MetricSummary& s = out->metrics[m];
      const bool higher_better = metric_higher_is_better(static_cast<Metric>(m));
      double sum = 0.0;
      int count = 0;
      for (std::size_t f = 0; f < frames.size(); ++f) {
        const LayerStats* stats = stats_of(frames[f]);
        if (!stats || !stats->metrics[m]) continue;
        const double v = *stats->metrics[m];
        sum += v;
        ++count;
        if (!s.worst || (higher_better ? v < *s.worst : v > *s.worst)) {
          s.worst = v;
          s.worst_index = static_cast<int>(f);
        }
      }
      if (count) s.mean = sum / count;
    }
  };

  for (const CompareResult& frame : frames) {
    for (const LayerStats& layer : frame.layers) {
      const bool seen = std::any_of(summary.layers.begin(), summary.layers.end(),
                                    [&](const LayerSummary& s) { return s.name == layer.name; });
      if (!seen) summary.layers.push_back(LayerSummary{layer.name, {}});
    }
  }
  for (LayerSummary& layer : summary.layers) {
    summarize_layer(&layer, [&](const CompareResult& frame) -> const LayerStats* {
      for (const LayerStats& s : frame.layers)
        if (s.name == layer.name) return &s;
      return nullptr;
    });
  }
  summarize_layer(&summary.overall,
                  [](const CompareResult& frame) -> const LayerStats* { return &frame.overall; });
  return summary;
}

}  // namespace ssgi
