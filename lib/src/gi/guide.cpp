#include "gi/guide.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "buffers.h"
#include "gi/denoise.h"
#include "parallel.h"
#include "throw.h"

namespace ssgi::detail {
namespace {

// The residual filter's range terms (DenoiseSettings::normal_power, sigma_depth): normals within
// about 50 degrees, depths within about 20% of one plane still share their residual.
constexpr float kResidualNormalPower = 2.0f;
constexpr float kResidualSigmaDepth = 0.2f;

// The residual's local model: a constant plus a slope along each feature of a sample's surface,
// its normal's three components and its log depth. What ssgi gets wrong changes with the way a
// surface faces and how far back it stands (the side of a post facing a sunlit wall, the floor
// under a shelf), so a slope along them keeps what a constant would average across; fitted
// over the filter's neighbourhood, where many samples share a slope, it costs little noise.
constexpr int kFeatures = 5;  // 1, nx, ny, nz, log z
constexpr int kMomentsA = kFeatures * (kFeatures + 1) / 2;
constexpr int kMoments = kMomentsA + 3 * kFeatures;
// The ridge on each slope, as a share of the neighbourhood's weight: at least kRidge, so that a
// slope a neighbourhood does not pin down (a plane's normal does not vary) stays near 0 instead
// of fitting noise, and kNoiseRidge times the guide's relative noise there (its variance over
// its squared level) where that is more, so that a noisier guide (one sample, half resolution, a
// lamplit room's rare bright samples) leans on the constant and a cleaner one on its slopes.
constexpr double kRidge = 0.01;
constexpr double kNoiseRidge = 0.03;

// The guide pixels of a trace sample, on the guide's pixel lattice: [x0, x1) x [y0, y1).
struct GuideRect {
  int x0, y0, x1, y1;
};

// The sum of a channel's guide values on a surface, and their count.
struct Moments {
  double sum = 0;
  int n = 0;
  void add(double v) {
    sum += v;
    ++n;
  }
};

// The smooth part of channels `channels` of `residual` where `known` (1 or 0; the same for each
// of them) is set: at each sample, the weighted least-squares fit of the residual to
// a + b . f(q) over the samples q the pyramid (`filter`) averages into it, evaluated at the
// sample's own features f(p) (normal and log depth less `log_depth_offset`, which keeps the
// moments' float sums well conditioned), with a ridge on the slopes from the guide's noise
// there (`noise_sum`, its variance filtered as the moments are) against its level (`light`'s
// plus the mean residual). The weighted sums of f f^T and f r are filtered as images and each
// sample solves its 5 x 5 system. Writes those channels of `smooth` and of `weight`, the known
// weight around each sample (0: nothing to fit, the smooth part 0).
template <typename Filter>
void fit_residual(const Image& residual, const std::vector<int>& channels, const float* known,
                  const Image& depth, const Image& normal, float log_depth_offset,
                  const Filter& filter, const Image& noise_sum, const Image& light, Image* smooth,
                  Image* weight) {
  const int w = residual.width(), h = residual.height();
  const int count = static_cast<int>(channels.size());
  const auto features = [&](std::size_t p, double* f) {
    f[0] = 1;
    for (int i = 0; i < 3; ++i) f[1 + i] = normal.plane(i)[p];
    f[4] = std::log(depth.plane(0)[p]) - log_depth_offset;
  };
  const int total_moments = kMomentsA + kFeatures * count;
  std::vector<Image> moments;
  for (int m = 0; m < total_moments; m += 3) moments.emplace_back(w, h, 3);
  const auto moment = [&](int m, std::size_t p) -> float& {
    return moments[m / 3].plane(m % 3)[p];
  };
  const auto row_of = [w](int y) {
    return std::pair<std::size_t, std::size_t>(static_cast<std::size_t>(y) * w,
                                               static_cast<std::size_t>(y + 1) * w);
  };
  parallel_for_rows(h, [&](int y) {
    const auto [begin, end] = row_of(y);
    for (std::size_t p = begin; p < end; ++p) {
      const bool on = known[p] > 0;
      double f[kFeatures] = {};
      if (on) features(p, f);
      int m = 0;
      for (int i = 0; i < kFeatures; ++i)
        for (int j = i; j < kFeatures; ++j) moment(m++, p) = static_cast<float>(f[i] * f[j]);
      for (int i = 0; i < kFeatures; ++i)
        for (int c : channels)
          moment(m++, p) = on ? static_cast<float>(f[i] * residual.plane(c)[p]) : 0.0f;
      for (; m < static_cast<int>(3 * moments.size()); ++m) moment(m, p) = 0;
    }
  });
  for (Image& image : moments) image = filter(image);
  parallel_for_rows(h, [&](int y) {
    const auto [begin, end] = row_of(y);
    for (std::size_t p = begin; p < end; ++p) {
      const double total = moment(0, p);
      for (int c : channels) {
        smooth->plane(c)[p] = 0;
        weight->plane(c)[p] = 0;
      }
      if (!(total > 0) || !std::isfinite(depth.plane(0)[p])) continue;
      // A (symmetric; positive definite with the ridge) in its lower triangle, factored in
      // place as L L^T (Cholesky); the right-hand sides, one per channel.
      double a[kFeatures][kFeatures], b[kFeatures][3];
      int m = 0;
      for (int i = 0; i < kFeatures; ++i)
        for (int j = i; j < kFeatures; ++j) a[j][i] = moment(m++, p);
      for (int i = 0; i < kFeatures; ++i)
        for (int k = 0; k < count; ++k) b[i][k] = moment(m++, p);
      // The guide's level here: the sample's light plus the neighbourhood's mean residual.
      double noise = 0, level = 0;
      for (int k = 0; k < count; ++k) {
        const int c = channels[k];
        noise += noise_sum.plane(c)[p] / total;
        const double guide_level = b[0][k] / total + light.plane(c)[p];
        level += guide_level * guide_level;
      }
      const double ridge = level > 0 ? std::clamp(kNoiseRidge * noise / level, kRidge, 1.0) : 1.0;
      for (int i = 1; i < kFeatures; ++i) a[i][i] += ridge * total;
      bool factored = true;
      for (int j = 0; j < kFeatures && factored; ++j) {
        double d = a[j][j];
        for (int k = 0; k < j; ++k) d -= a[j][k] * a[j][k];
        factored = d > 1e-12 * total;
        if (!factored) break;
        a[j][j] = std::sqrt(d);
        for (int i = j + 1; i < kFeatures; ++i) {
          double v = a[i][j];
          for (int k = 0; k < j; ++k) v -= a[i][k] * a[j][k];
          a[i][j] = v / a[j][j];
        }
      }
      double f[kFeatures];
      features(p, f);
      for (int k = 0; k < count; ++k) {
        double value = b[0][k] / total;  // the plain mean, where the system is singular
        if (factored) {
          double z[kFeatures], x[kFeatures];
          for (int i = 0; i < kFeatures; ++i) {
            double v = b[i][k];
            for (int j = 0; j < i; ++j) v -= a[i][j] * z[j];
            z[i] = v / a[i][i];
          }
          value = 0;
          for (int i = kFeatures - 1; i >= 0; --i) {
            double v = z[i];
            for (int j = i + 1; j < kFeatures; ++j) v -= a[j][i] * x[j];
            x[i] = v / a[i][i];
            value += f[i] * x[i];
          }
        }
        smooth->plane(channels[k])[p] = std::isfinite(value) ? static_cast<float>(value) : 0.0f;
        weight->plane(channels[k])[p] = static_cast<float>(total);
      }
    }
  });
}

}  // namespace

GuideOnGrid guide_on_grid(const GBuffer& frame, const GBuffer& grid, int scale,
                          const GuideFrame& guide, float thickness) {
  const int gw = grid.width(), gh = grid.height();
  const int f = guide.fraction;
  const int lw = guide.light.width(), lh = guide.light.height();
  // Data-window pixels to the guide's lattice (the guide covers the shot's display window).
  const int ox = frame.data_window.x0 - frame.display_window.x0;
  const int oy = frame.data_window.y0 - frame.display_window.y0;
  const auto lattice = [&](int v, int offset, int size) {
    const int d = v + offset;
    return std::clamp(d >= 0 ? d / f : -1, 0, size - 1);
  };
  GuideOnGrid out;
  out.mean = Image(gw, gh, 3);
  out.variance = Image(gw, gh, 3);
  out.known = Image(gw, gh, 3);
  const float* zg = guide.depth.plane(0);
  const std::size_t pixels = static_cast<std::size_t>(lw) * lh;
  // Per guide pixel, once: whether it gives channel c (a surface whose frame pixel at its centre
  // has albedo: an emitter's diffuse light is 0 in a renderer's pass, which says nothing of the
  // light around it; and where the pass is known), and its squared second differences along x
  // and y where both neighbours give c on its own surface (within `thickness` of its depth),
  // each over 1.5, with their count: a ramp's are 0, a smooth light's small, and iid noise of
  // variance s^2 gives a squared difference v - (left + right) / 2 of 1.5 s^2. The light's own
  // slope is not taken for noise, so that a guide without noise has none.
  const bool with_albedo = !frame.albedo.empty();
  // Written for every pixel (gives) or read only where written (the rest): no zeroing, which
  // at 1080p would fault in 30 MB a frame before any use.
  UninitializedVector<std::uint8_t> gives(pixels * 3), differences(pixels * 3);
  UninitializedVector<float> squares(pixels * 3);
  parallel_for_rows(lh, [&](int y) {
    for (int x = 0; x < lw; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * lw + x;
      bool reflects = std::isfinite(zg[q]);
      const int fx = x * f + f / 2 - ox, fy = y * f + f / 2 - oy;
      if (reflects && with_albedo && fx >= 0 && fy >= 0 && fx < frame.width() &&
          fy < frame.height()) {
        const std::size_t p = static_cast<std::size_t>(fy) * frame.width() + fx;
        reflects = frame.albedo.plane(0)[p] != 0 || frame.albedo.plane(1)[p] != 0 ||
                   frame.albedo.plane(2)[p] != 0;
      }
      for (int c = 0; c < 3; ++c)
        gives[c * pixels + q] = reflects && (guide.known.empty() || guide.known.plane(c)[q] != 0);
    }
  });
  parallel_for_rows(lh, [&](int y) {
    for (int x = 0; x < lw; ++x) {
      const std::size_t q = static_cast<std::size_t>(y) * lw + x;
      const float z = zg[q];
      const auto near = [&](std::size_t n) { return std::fabs(zg[n] - z) <= thickness * z; };
      for (int c = 0; c < 3; ++c) {
        const std::uint8_t* g = gives.data() + c * pixels;
        if (!g[q]) continue;
        const float* v = guide.light.plane(c);
        double sum = 0;
        int n = 0;
        if (x > 0 && x + 1 < lw && g[q - 1] && g[q + 1] && near(q - 1) && near(q + 1)) {
          const double d = v[q] - 0.5 * (v[q - 1] + v[q + 1]);
          sum += d * d / 1.5;
          ++n;
        }
        if (y > 0 && y + 1 < lh && g[q - lw] && g[q + lw] && near(q - lw) && near(q + lw)) {
          const double d = v[q] - 0.5 * (v[q - lw] + v[q + lw]);
          sum += d * d / 1.5;
          ++n;
        }
        squares[c * pixels + q] = static_cast<float>(sum);
        differences[c * pixels + q] = static_cast<std::uint8_t>(n);
      }
    }
  });
  parallel_for_rows(gh, [&](int by) {
    for (int bx = 0; bx < gw; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * gw + bx;
      const float zs = grid.depth.plane(0)[s];
      if (!std::isfinite(zs)) continue;
      const int x0 = bx * scale, y0 = by * scale;
      const int x1 = std::min(x0 + scale, frame.width()) - 1;
      const int y1 = std::min(y0 + scale, frame.height()) - 1;
      const GuideRect block{lattice(x0, ox, lw), lattice(y0, oy, lh), lattice(x1, ox, lw) + 1,
                            lattice(y1, oy, lh) + 1};
      // A block narrower than three guide pixels grown by one each side, so that its noise is
      // seen over a few pixels; a wider one shows it on its own.
      const int gx = block.x1 - block.x0 < 3 ? 1 : 0, gy = block.y1 - block.y0 < 3 ? 1 : 0;
      const GuideRect grown{std::max(block.x0 - gx, 0), std::max(block.y0 - gy, 0),
                            std::min(block.x1 + gx, lw), std::min(block.y1 + gy, lh)};
      Moments in_block[3], around[3];
      double noise[3] = {0, 0, 0};
      int noise_n[3] = {0, 0, 0};
      for (int y = grown.y0; y < grown.y1; ++y)
        for (int x = grown.x0; x < grown.x1; ++x) {
          const std::size_t q = static_cast<std::size_t>(y) * lw + x;
          // On the sample's surface: within `thickness` of its depth.
          if (!(std::fabs(zg[q] - zs) <= thickness * zs)) continue;
          const bool inside = x >= block.x0 && x < block.x1 && y >= block.y0 && y < block.y1;
          for (int c = 0; c < 3; ++c) {
            if (!gives[c * pixels + q]) continue;
            const double value = guide.light.plane(c)[q];
            around[c].add(value);
            if (inside) in_block[c].add(value);
            noise[c] += squares[c * pixels + q];
            noise_n[c] += differences[c * pixels + q];
          }
        }
      for (int c = 0; c < 3; ++c) {
        if (around[c].n == 0) continue;
        const Moments& mean = in_block[c].n > 0 ? in_block[c] : around[c];
        out.mean.plane(c)[s] = static_cast<float>(mean.sum / mean.n);
        // A surface too small to show noise (a pixel or two wide both ways) is its own
        // neighbourhood for the denoiser too: the guide's mean is kept there as it is.
        out.variance.plane(c)[s] =
            noise_n[c] > 0 ? static_cast<float>(noise[c] / noise_n[c] / mean.n) : 0.0f;
        out.known.plane(c)[s] = 1.0f;
      }
    }
  });
  return out;
}

Image guided_light(const Image& light, const GuideOnGrid& guide, const Image& grid_depth,
                   const Image& grid_normal, int level, const DenoiseSettings& settings,
                   GuideReport* report) {
  const int w = light.width(), h = light.height();
  for (const Image* image : {&guide.mean, &guide.variance, &guide.known, &grid_depth, &grid_normal})
    if (image->width() != w || image->height() != h || light.channels() != 3)
      throw Error(ErrorKind::kInternal, "", "guided_light: images of different sizes");
  // The residual's pyramid goes as deep as the light's, with looser edges: what ssgi gets wrong
  // follows the geometry less sharply than the light does, and the light's edges leave pixels
  // of fine geometry (grass, rods) belonging to no coarser sample, so unfiltered
  // (tests/accuracy/README.md, "Guides", has the measurements). It is built from the grid's own
  // depth and normals, the grid its level 0: twelve filters a frame where the channels share one
  // fit (ten for its moments, the noise, the detail's energy), each a pyramid of the grid's size
  // rather than of the frame's.
  DenoiseSettings residual_settings = settings;
  residual_settings.levels = std::max(settings.levels, level) - level;
  residual_settings.normal_power = kResidualNormalPower;
  residual_settings.sigma_depth = kResidualSigmaDepth;
  // The pyramid filters each channel as a convex combination over a surface: filtering a value
  // times its weight and the weight alike, their ratio is the mean over the known samples alone
  // (normalised convolution).
  const auto filter = [&](const Image& image) {
    return upsample_and_denoise(image, 0, grid_depth, grid_normal, residual_settings, true, 0);
  };
  // The residual where the guide knows each channel. The channels share one fit where they are
  // known at the same samples (the moments of the features are then the same for all three);
  // where they are not (a pass with albedo divided by an albedo with a channel at 0), each
  // channel is fitted on its own.
  const std::size_t n = light.plane_size();
  Image residual(w, h, 3), noise_in(w, h, 3);
  double log_depth_sum = 0;
  std::size_t surfaces = 0;
  bool same_known = true;
  for (std::size_t p = 0; p < n; ++p) {
    for (int c = 0; c < 3; ++c) {
      const bool on = guide.known.plane(c)[p] > 0;
      residual.plane(c)[p] = on ? guide.mean.plane(c)[p] - light.plane(c)[p] : 0.0f;
      noise_in.plane(c)[p] = on ? guide.variance.plane(c)[p] : 0.0f;
      same_known = same_known && on == (guide.known.plane(0)[p] > 0);
    }
    if (guide.known.plane(0)[p] > 0 && std::isfinite(grid_depth.plane(0)[p])) {
      log_depth_sum += std::log(grid_depth.plane(0)[p]);
      ++surfaces;
    }
  }
  const float log_depth_offset =
      surfaces > 0 ? static_cast<float>(log_depth_sum / static_cast<double>(surfaces)) : 0.0f;
  const Image noise = filter(noise_in);
  Image smooth(w, h, 3), weight(w, h, 3);
  const auto fit = [&](const std::vector<int>& channels) {
    fit_residual(residual, channels, guide.known.plane(channels.front()), grid_depth, grid_normal,
                 log_depth_offset, filter, noise, light, &smooth, &weight);
  };
  if (same_known) {
    fit({0, 1, 2});
  } else {
    for (int c = 0; c < 3; ++c) fit({c});
  }
  // The detail the fit leaves, its local energy and the guide's noise there, on the known
  // samples, each over the same weight.
  Image detail(w, h, 3), energy_in(w, h, 3);
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < n; ++p) {
      const bool on = guide.known.plane(c)[p] > 0;
      const float d = on ? residual.plane(c)[p] - smooth.plane(c)[p] : 0.0f;
      detail.plane(c)[p] = d;
      energy_in.plane(c)[p] = d * d;
    }
  const Image energy = filter(energy_in);
  Image out(w, h, 3);
  double residual_sum = 0, out_sum = 0, kept_sum = 0;
  std::size_t surface = 0, known = 0;
  for (std::size_t p = 0; p < out.plane_size(); ++p) {
    if (!std::isfinite(grid_depth.plane(0)[p])) continue;
    bool any_known = false;
    for (int c = 0; c < 3; ++c) {
      const float wt = weight.plane(c)[p];
      float kept = 0;
      if (wt > 0 && guide.known.plane(c)[p] > 0) {
        const float e = energy.plane(c)[p] / wt, n = noise.plane(c)[p] / wt;
        kept = e > 0 ? std::max(0.0f, e - n) / e : 0.0f;
        any_known = true;
      }
      const float r = smooth.plane(c)[p] + kept * detail.plane(c)[p];
      const float v = std::max(0.0f, light.plane(c)[p] + r);
      out.plane(c)[p] = v;
      residual_sum += v - light.plane(c)[p];
      out_sum += v;
      kept_sum += kept;
    }
    known += any_known ? 1 : 0;
    ++surface;
  }
  if (report) {
    report->residual_share = out_sum > 0 ? residual_sum / out_sum : 0.0;
    report->detail_kept = known > 0 ? kept_sum / (3.0 * static_cast<double>(known)) : 0.0;
    report->known_share = surface > 0 ? static_cast<double>(known) / surface : 0.0;
  }
  return out;
}

}  // namespace ssgi::detail
