#include "gi/guide.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
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

// `image` (3 channels) with each channel multiplied by `weight`'s.
Image weighted(const Image& image, const Image& weight) {
  Image out(image.width(), image.height(), 3);
  for (int c = 0; c < 3; ++c) {
    const float* a = image.plane(c);
    const float* w = weight.plane(c);
    float* o = out.plane(c);
    parallel_for_rows(image.height(), [&](int y) {
      const std::size_t row = static_cast<std::size_t>(y) * image.width();
      for (int x = 0; x < image.width(); ++x) o[row + x] = a[row + x] * w[row + x];
    });
  }
  return out;
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
  // depth and normals, the grid its level 0: four filters a frame, each a pyramid of the grid's
  // size rather than of the frame's.
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
  Image residual(w, h, 3);
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < residual.plane_size(); ++p)
      residual.plane(c)[p] =
          guide.known.plane(c)[p] > 0 ? guide.mean.plane(c)[p] - light.plane(c)[p] : 0.0f;
  const Image weight = filter(guide.known);
  const Image smooth_sum = filter(weighted(residual, guide.known));
  Image smooth(w, h, 3), detail(w, h, 3), energy_in(w, h, 3);
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < smooth.plane_size(); ++p) {
      const float wt = weight.plane(c)[p];
      const float r = wt > 0 ? smooth_sum.plane(c)[p] / wt : 0.0f;
      smooth.plane(c)[p] = r;
      const float d = guide.known.plane(c)[p] > 0 ? residual.plane(c)[p] - r : 0.0f;
      detail.plane(c)[p] = d;
      energy_in.plane(c)[p] = d * d;
    }
  const Image energy = filter(energy_in);
  const Image noise = filter(weighted(guide.variance, guide.known));
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
