// The denoise stage: the seed's bilateral pyramid (Sachdeva 2022), made plane-aware.
//
// Level 0 is the input; each coarser level halves the size, every 2x2 block becoming one sample
// of one surface. The coarsest level is filtered with a joint bilateral filter, and each finer
// level is rebuilt from the one below by joint bilateral upsampling (Kopf et al. 2007) and a
// small edge-aware blur. Every weight is a spatial term times `range_weight`, which is ~0
// between different surfaces, so light does not cross depth edges, creases or background.
#include "gi/denoise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "buffers.h"
#include "gi/denoise_kernels.h"
#include "parallel.h"
#include "throw.h"

namespace ssgi::detail {
namespace {

// A pyramid level's guides, one plane per field of Surface: the upsampling kernel reads
// consecutive pixels of each.
struct Guides {
  int width = 0, height = 0;
  UninitializedVector<float> z, nx, ny, nz, gx, gy;
  Guides() = default;
  // Background everywhere, written in parallel (a 1080p frame's second level is 12 MB).
  Guides(int w, int h)
      : width(w),
        height(h),
        z(static_cast<std::size_t>(w) * h),
        nx(z.size()),
        ny(z.size()),
        nz(z.size()),
        gx(z.size()),
        gy(z.size()) {
    parallel_for_rows(h, [&](int y) {
      const std::size_t row = static_cast<std::size_t>(y) * w;
      std::fill_n(z.data() + row, w, kInf);
      for (auto* plane : {&nx, &ny, &nz, &gx, &gy}) std::fill_n(plane->data() + row, w, 0.0f);
    });
  }
  Surface at(std::size_t i) const { return {z[i], nx[i], ny[i], nz[i], gx[i], gy[i]}; }
  GuidePlanes planes() const {
    return {z.data(), nx.data(), ny.data(), nz.data(), gx.data(), gy.data(), width, height};
  }
};

// A level's guides and, from the level the light enters at down to the coarsest, its light
// (3 channels, 0 on background); finer levels have none of their own.
struct Level {
  Image radiance;
  Guides guides;
};

void compute_depth_gradient(Guides& guides) {
  const std::size_t w = guides.width;
  parallel_for_rows(guides.height, [&](int y) {
    depth_gradient_row(guides.z.data(), guides.width, guides.height, y, guides.gx.data() + y * w,
                       guides.gy.data() + y * w);
  });
}

// Level 0's guides: the inputs with anything unusable made explicit, so that later passes
// need not check. A depth that is not finite and positive is background (+inf); a normal that
// cannot be normalised is unknown (0). The depths are kept whole (the gradients read two rows
// either side); the other fields are made a window of rows at a time (rows()), since the
// passes that read level 0 when the light enters coarser (halving it, the last upsampling)
// read a row or two at a time: no full-resolution planes of normals and gradients.
class BaseGuides {
 public:
  BaseGuides(const Image& depth, const Image& normal)
      : width_(depth.width()),
        height_(depth.height()),
        normal_(normal),
        z_(static_cast<std::size_t>(width_) * height_) {  // every value written below
    parallel_for_rows(height_, [&](int y) {
      const std::size_t row = static_cast<std::size_t>(y) * width_;
      const float* in = depth.plane(0) + row;
      float* out = z_.data() + row;
      for (int x = 0; x < width_; ++x) out[x] = std::isfinite(in[x]) && in[x] > 0 ? in[x] : kInf;
    });
  }

  int width() const { return width_; }
  int height() const { return height_; }
  const UninitializedVector<float>& z() const { return z_; }

  // Rows [y0, y0 + rows) of the guides (clipped to the level), in `scratch`, valid while it is
  // and until its next use.
  GuidePlanes rows(int y0, int rows, std::vector<float>* scratch) const {
    rows = std::min(rows, height_ - y0);
    const std::size_t n = static_cast<std::size_t>(rows) * width_;
    scratch->resize(5 * n);
    float* const nx = scratch->data();
    float *const ny = nx + n, *const nz = ny + n, *const gx = nz + n, *const gy = gx + n;
    for (int r = 0; r < rows; ++r) {
      const std::size_t at = static_cast<std::size_t>(r) * width_;
      fill_row(y0 + r, nx + at, ny + at, nz + at, gx + at, gy + at);
    }
    GuidePlanes planes{
        z_.data() + static_cast<std::size_t>(y0) * width_, nx, ny, nz, gx, gy, width_, height_};
    planes.y0 = y0;
    return planes;
  }

  // Row y's normals and depth gradients.
  void fill_row(int y, float* nx, float* ny, float* nz, float* gx, float* gy) const {
    const std::size_t row = static_cast<std::size_t>(y) * width_;
    const float* z = z_.data() + row;
    const float *in_x = normal_.plane(0) + row, *in_y = normal_.plane(1) + row,
                *in_z = normal_.plane(2) + row;
    for (int x = 0; x < width_; ++x) {
      nx[x] = ny[x] = nz[x] = 0.0f;
      if (!is_surface(z[x])) continue;
      const float length = std::sqrt(in_x[x] * in_x[x] + in_y[x] * in_y[x] + in_z[x] * in_z[x]);
      if (length > 0 && std::isfinite(length)) {
        nx[x] = in_x[x] / length;
        ny[x] = in_y[x] / length;
        nz[x] = in_z[x] / length;
      }
    }
    depth_gradient_row(z_.data(), width_, height_, y, gx, gy);
  }

 private:
  int width_, height_;
  const Image& normal_;
  UninitializedVector<float> z_;
};

// Level 0's guides as whole planes, for a pyramid whose light enters at level 0 (filtered and
// blurred there, which reads windows of rows around every pixel).
Guides make_base_guides(const BaseGuides& base) {
  const int w = base.width(), h = base.height();
  Guides guides;
  guides.width = w;
  guides.height = h;
  guides.z = base.z();
  const std::size_t n = guides.z.size();
  // Every value written below.
  for (auto* plane : {&guides.nx, &guides.ny, &guides.nz, &guides.gx, &guides.gy}) plane->resize(n);
  parallel_for_rows(h, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    base.fill_row(y, guides.nx.data() + row, guides.ny.data() + row, guides.nz.data() + row,
                  guides.gx.data() + row, guides.gy.data() + row);
  });
  return guides;
}

// `light` where `guides` has a surface and the light is finite, else 0.
Image light_on_surfaces(const Image& light, const Guides& guides) {
  if (light.width() != guides.width || light.height() != guides.height || light.channels() != 3)
    throw Error(ErrorKind::kInternal, {}, "denoise: light does not match its pyramid level");
  Image out(guides.width, guides.height, 3);
  parallel_for_rows(guides.height, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * guides.width;
    for (int c = 0; c < 3; ++c)
      for (std::size_t i = row; i < row + guides.width; ++i) {
        const float v = light.plane(c)[i];
        out.plane(c)[i] = is_surface(guides.z[i]) && std::isfinite(v) ? v : 0.0f;
      }
  });
  return out;
}

// Halves a level of fine_width x fine_height (rounding up), block by block (downsample_row),
// carrying the light down when the fine level has any (`fine_light`, else null); then the
// coarse level's depth gradients. fine_rows(y, scratch) gives the fine guides holding rows 2y
// and 2y + 1.
template <typename FineRows>
Level halve(int fine_width, int fine_height, const FineRows& fine_rows, const Image* fine_light,
            const RangeTerms& terms) {
  const int w = (fine_width + 1) / 2, h = (fine_height + 1) / 2;
  const bool with_light = fine_light != nullptr;
  Level coarse{with_light ? Image(w, h, 3) : Image(), Guides(w, h)};
  Guides& cg = coarse.guides;
  const float* const light_in[3] = {with_light ? fine_light->plane(0) : nullptr,
                                    with_light ? fine_light->plane(1) : nullptr,
                                    with_light ? fine_light->plane(2) : nullptr};
  parallel_for_rows(h, [&](int y) {
    thread_local std::vector<float> scratch;
    const std::size_t row = static_cast<std::size_t>(y) * w;
    const GuideRow out{cg.z.data() + row, cg.nx.data() + row, cg.ny.data() + row,
                       cg.nz.data() + row};
    float* const light_out[3] = {with_light ? coarse.radiance.plane(0) + row : nullptr,
                                 with_light ? coarse.radiance.plane(1) + row : nullptr,
                                 with_light ? coarse.radiance.plane(2) + row : nullptr};
    downsample_row(fine_rows(y, &scratch), light_in, y, w, terms, out, light_out);
  });
  compute_depth_gradient(cg);
  return coarse;
}

Level downsample_with_guides(const Level& fine, const RangeTerms& terms) {
  const Guides& fg = fine.guides;
  const bool with_light =
      fine.radiance.width() == fg.width && fine.radiance.height() == fg.height && fg.width > 0;
  const GuidePlanes planes = fg.planes();
  return halve(
      fg.width, fg.height, [&](int, std::vector<float>*) { return planes; },
      with_light ? &fine.radiance : nullptr, terms);
}

Level downsample_base(const BaseGuides& base, const RangeTerms& terms) {
  return halve(
      base.width(), base.height(),
      [&](int y, std::vector<float>* scratch) { return base.rows(2 * y, 2, scratch); }, nullptr,
      terms);
}

// Gaussian weights exp(-k^2 / (2 sigma^2)) for k = 0..radius.
std::vector<float> gaussian_taps(int radius, float sigma) {
  std::vector<float> taps(radius + 1);
  for (int k = 0; k <= radius; ++k) taps[k] = std::exp(-0.5f * (k / sigma) * (k / sigma));
  return taps;
}

// Joint bilateral filter of `radiance` guided by `guides` (joint_bilateral_row): a square
// window of `radius`, a spatial Gaussian times `range_weight`. Used both at the coarsest level
// and as the blur after each upsampling step.
Image joint_bilateral(const Image& radiance, const Guides& guides, int radius, float sigma_spatial,
                      const RangeTerms& terms) {
  const int w = radiance.width(), h = radiance.height();
  const std::vector<float> taps = gaussian_taps(radius, sigma_spatial);
  Image out(w, h, 3);
  const GuidePlanes planes = guides.planes();
  const float* const light[3] = {radiance.plane(0), radiance.plane(1), radiance.plane(2)};
  parallel_for_rows(h, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    float* const out_at[3] = {out.plane(0) + row, out.plane(1) + row, out.plane(2) + row};
    joint_bilateral_row(planes, light, y, radius, taps.data(), terms, out_at);
  });
  return out;
}

// Joint bilateral upsampling (Kopf et al. 2007) of `coarse_light` to the finer level of w x h
// whose guides fine_rows(y, scratch) gives from row y on (the upsample_row kernel). A fine
// pixel's own value, which it keeps where no coarse sample resembles it, is that of `own` at
// (x >> own_shift, y >> own_shift): the level's own light, or for a level finer than the
// light's, its block's.
template <typename FineRows>
Image bilateral_upsample(const Image& coarse_light, const Guides& coarse, int w, int h,
                         const FineRows& fine_rows, const Image& own, int own_shift,
                         const RangeTerms& terms) {
  Image out(w, h, 3);
  const GuidePlanes coarse_planes = coarse.planes();
  const float* const light[3] = {coarse_light.plane(0), coarse_light.plane(1),
                                 coarse_light.plane(2)};
  parallel_for_rows(h, [&](int y) {
    thread_local std::vector<float> own_row, scratch;
    own_row.resize(3 * static_cast<std::size_t>(w));
    const float* const own_at[3] = {own_row.data(), own_row.data() + w, own_row.data() + 2 * w};
    const std::size_t own_base = static_cast<std::size_t>(y >> own_shift) * own.width();
    for (int c = 0; c < 3; ++c)
      for (int x = 0; x < w; ++x) own_row[c * w + x] = own.plane(c)[own_base + (x >> own_shift)];
    const std::size_t row = static_cast<std::size_t>(y) * w;
    float* const out_at[3] = {out.plane(0) + row, out.plane(1) + row, out.plane(2) + row};
    // The kernel indexes out and own by x within the row.
    upsample_row(fine_rows(y, &scratch), y, coarse_planes, light, own_at, terms, out_at);
  });
  return out;
}

void check_shapes(const Image& depth, const Image& normal) {
  if (depth.channels() != 1 || normal.channels() != 3 || normal.width() != depth.width() ||
      normal.height() != depth.height()) {
    throw Error(ErrorKind::kInternal, {},
                "denoise: expected 1-channel depth and 3-channel normal of one size");
  }
}

}  // namespace

void validate_denoise_settings(const DenoiseSettings& s) {
  // Named by the command line's options (the pyramid's depth has none: it follows the trace
  // grid and the preset).
  auto fail = [](const std::string& what, double value) {
    std::ostringstream v;
    v << value;
    throw_usage(what + " (got " + v.str() + ")");
  };
  if (s.levels < 0) fail("the denoiser's pyramid levels must be >= 0", s.levels);
  if (s.radius < 0) fail("--denoise-radius must be >= 0", s.radius);
  if (s.upsample_blur_radius < 0) fail("--denoise-blur must be >= 0", s.upsample_blur_radius);
  if (!(s.sigma_spatial > 0 && std::isfinite(s.sigma_spatial)))
    fail("--denoise-sigma-spatial must be positive", s.sigma_spatial);
  if (!(s.sigma_depth > 0 && std::isfinite(s.sigma_depth)))
    fail("--denoise-sigma-depth must be positive", s.sigma_depth);
  if (!(s.normal_power >= 0 && std::isfinite(s.normal_power)))
    fail("--denoise-normal-power must be >= 0", s.normal_power);
}

Image denoise_pyramid(const Image& noisy, const Image& depth, const Image& normal,
                      const DenoiseSettings& settings) {
  return upsample_and_denoise(noisy, 0, depth, normal, settings, true);
}

Image upsample_and_denoise(const Image& light, int light_level, const Image& depth,
                           const Image& normal, const DenoiseSettings& settings, bool denoise,
                           int output_level) {
  validate_denoise_settings(settings);
  const int w = depth.width(), h = depth.height();
  if (w == 0 || h == 0) return Image(w, h, 3);
  const RangeTerms terms = make_range_terms(settings);

  // The guides at every level down to the coarser of the light's and the filter's; the light
  // enters at its own level and is carried down from there.
  check_shapes(depth, normal);
  const BaseGuides base(depth, normal);
  // Level 0's guides are whole planes only where the light enters there (filtered and blurred
  // at level 0); otherwise the passes that read level 0 make its rows as they go.
  const bool whole_base = light_level == 0;
  std::vector<Level> levels(1);
  auto enter = [&](Level& level) { level.radiance = light_on_surfaces(light, level.guides); };
  if (whole_base) {
    levels.front().guides = make_base_guides(base);
    enter(levels.front());
  }
  const int deepest = denoise ? std::max(settings.levels, light_level) : light_level;
  // A 1x1 level cannot shrink further; more levels would repeat it (and the light of a 1x1
  // grid enters there).
  bool entered = whole_base;
  auto can_shrink = [&] {
    if (levels.size() == 1) return base.width() > 1 || base.height() > 1;
    return levels.back().guides.width > 1 || levels.back().guides.height > 1;
  };
  while (static_cast<int>(levels.size()) <= deepest && can_shrink()) {
    levels.push_back(levels.size() == 1 && !whole_base
                         ? downsample_base(base, terms)
                         : downsample_with_guides(levels.back(), terms));
    if (static_cast<int>(levels.size()) - 1 == light_level) {
      enter(levels.back());
      entered = true;
    }
  }
  if (!entered) {
    if (levels.size() == 1) levels.front().guides = make_base_guides(base);  // a 1x1 frame
    enter(levels.back());
  }
  const int coarsest = static_cast<int>(levels.size()) - 1;
  const int entry = std::min(light_level, coarsest);

  Image out = denoise ? joint_bilateral(levels.back().radiance, levels.back().guides,
                                        settings.radius, settings.sigma_spatial, terms)
                      : levels.back().radiance;
  for (int l = coarsest - 1; l >= std::min(output_level, coarsest); --l) {
    // Finer than the light's level there is no light of a pixel's own: each keeps its block's
    // where no coarse sample resembles it.
    const int own_level = std::max(l, entry);
    const Image& own = levels[own_level].radiance;
    if (l == 0 && levels.front().guides.width == 0) {
      out = bilateral_upsample(
          out, levels[1].guides, base.width(), base.height(),
          [&](int y, std::vector<float>* scratch) { return base.rows(y, 1, scratch); }, own,
          own_level, terms);
    } else {
      const GuidePlanes fine = levels[l].guides.planes();
      out = bilateral_upsample(
          out, levels[l + 1].guides, fine.width, fine.height,
          [&](int, std::vector<float>*) { return fine; }, own, own_level - l, terms);
    }
    // Finer than the traced light there is no noise of its own to blur, only the upsampling's
    // steps, which the depth-aware taps already follow: a blur there would cost time and hardly
    // change the light.
    if (denoise && settings.upsample_blur_radius > 0 && l >= entry) {
      // The blur's spatial sigma is its radius: a gentle 3x3 at the default radius 1.
      out = joint_bilateral(out, levels[l].guides, settings.upsample_blur_radius,
                            settings.upsample_blur_radius, terms);
    }
  }
  return out;
}

}  // namespace ssgi::detail
