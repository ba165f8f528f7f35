// Every SIMD kernel against its scalar twin, on every SIMD target this CPU and build have
// (ssgi::simd_targets: AVX2, SSE4, ... and Highway's portable ones): bit for bit, on odd sizes
// (every tail length) and on the values that take the kernels' other branches (background,
// NaN, unknown normals, back-facing normals, overflowing depth differences).
#include "simd.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "gi/denoise_kernels.h"
#include "gi/slice_kernel.h"

namespace ssgi::detail {
namespace {

// Each test runs once per target, pinned with set_simd_target.
class SimdTarget : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override { set_simd_target(GetParam()); }
  void TearDown() override { set_simd_target("auto"); }
};

// The targets to pin: every one but "auto" and "scalar" (the twins themselves).
std::vector<std::string> pinned_targets() {
  std::vector<std::string> targets = simd_targets();
  targets.erase(std::remove_if(targets.begin(), targets.end(),
                               [](const std::string& t) { return t == "auto" || t == "scalar"; }),
                targets.end());
  return targets;
}

Surface random_surface(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 19);
  Surface s;
  s.z = 1.0f + 10.0f * (u(rng) + 1.0f);
  float nx = u(rng), ny = u(rng), nz = u(rng);
  const float len = std::sqrt(nx * nx + ny * ny + nz * nz);
  s.nx = nx / len, s.ny = ny / len, s.nz = nz / len;
  s.gx = 0.1f * u(rng), s.gy = 0.1f * u(rng);
  switch (pick(rng)) {  // the rare values, each about 1 in 20
    case 0:
      s.nx = s.ny = s.nz = 0;  // unknown normal
      break;
    case 1:
      s.z = std::numeric_limits<float>::quiet_NaN();
      break;
    case 2:
      s.z = std::numeric_limits<float>::infinity();
      break;
    case 3:
      s.gx = 3e38f;  // the extrapolated depth overflows
      break;
    case 4:
      s.z = 1e-30f;
      break;
    default:
      break;
  }
  return s;
}

// Guide planes of w x h random surfaces (random_surface's rare values included).
struct RandomGuides {
  std::vector<float> z, nx, ny, nz, gx, gy;
  int width, height;
  RandomGuides(std::mt19937& rng, int w, int h) : width(w), height(h) {
    for (int k = 0; k < w * h; ++k) {
      const Surface s = random_surface(rng);
      z.push_back(s.z), nx.push_back(s.nx), ny.push_back(s.ny), nz.push_back(s.nz);
      gx.push_back(s.gx), gy.push_back(s.gy);
    }
  }
  GuidePlanes planes() const {
    return {z.data(), nx.data(), ny.data(), nz.data(), gx.data(), gy.data(), width, height};
  }
};

// Random light in [0, 4) for upsampling to a fine row of width w from `coarse`: the coarse
// level's 3 planes and the fine row's own values.
struct UpsampleLight {
  std::vector<float> light, own;
  const float* coarse[3];
  const float* own_at[3];
  UpsampleLight(std::mt19937& rng, const RandomGuides& coarse_guides, int w)
      : light(3 * coarse_guides.z.size()), own(3 * static_cast<std::size_t>(w)) {
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    for (float& v : light) v = u(rng);
    for (float& v : own) v = u(rng);
    const std::size_t cn = coarse_guides.z.size();
    for (int c = 0; c < 3; ++c) coarse[c] = light.data() + c * cn, own_at[c] = own.data() + c * w;
  }
};

TEST_P(SimdTarget, UpsampleRowMatchesTheScalarTwinBitForBit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  std::size_t blended = 0;
  for (auto [w, h] : {std::pair{1, 1}, std::pair{2, 3}, std::pair{7, 5}, std::pair{17, 9},
                      std::pair{40, 6}, std::pair{33, 1}}) {
    const RandomGuides fine(rng, w, h), coarse(rng, (w + 1) / 2, (h + 1) / 2);
    const UpsampleLight random_light(rng, coarse, w);
    const float* const* coarse_light = random_light.coarse;
    const float* const* own_at = random_light.own_at;
    for (float power : {32.0f, 1.0f, 0.0f}) {
      DenoiseSettings settings;
      settings.normal_power = power;
      const RangeTerms terms = make_range_terms(settings);
      for (int y = 0; y < h; ++y) {
        std::vector<float> simd(3 * w + 1, -1.0f), scalar(3 * w, -2.0f);
        float* const simd_at[3] = {simd.data(), simd.data() + w, simd.data() + 2 * w};
        float* const scalar_at[3] = {scalar.data(), scalar.data() + w, scalar.data() + 2 * w};
        upsample_row(fine.planes(), y, coarse.planes(), coarse_light, own_at, terms, simd_at);
        upsample_row_scalar(fine.planes(), y, coarse.planes(), coarse_light, own_at, terms,
                            scalar_at);
        ASSERT_EQ(std::memcmp(simd.data(), scalar.data(), 3 * w * sizeof(float)), 0)
            << w << "x" << h << " row " << y << " power " << power;
        EXPECT_EQ(simd[3 * w], -1.0f);  // nothing written past the row
        for (int c = 0; c < 3; ++c)
          for (int x = 0; x < w; ++x) {
            const float v = scalar[c * w + x];
            if (!is_surface(fine.z[static_cast<std::size_t>(y) * w + x])) {
              EXPECT_EQ(v, 0.0f);
              continue;
            }
            EXPECT_GE(v, 0.0f);
            EXPECT_LE(v, 4.0f);
            blended += std::fabs(v - own_at[c][x]) > 1e-3f;
          }
      }
    }
  }
  EXPECT_GT(blended, 300u);  // the coarse light came through, not only the pixels' own
}

// Rows [y0, y0 + rows) of `g` copied out, as a window of its rows (the denoiser makes level 0's
// guides this way).
struct RowWindow {
  std::vector<float> z, nx, ny, nz, gx, gy;
  GuidePlanes window;
  RowWindow(const RandomGuides& g, int y0, int rows) {
    rows = std::min(rows, g.height - y0);
    const auto first = static_cast<std::ptrdiff_t>(y0) * g.width;
    const auto last = first + static_cast<std::ptrdiff_t>(rows) * g.width;
    for (auto [to, from] : {std::pair{&z, &g.z}, std::pair{&nx, &g.nx}, std::pair{&ny, &g.ny},
                            std::pair{&nz, &g.nz}, std::pair{&gx, &g.gx}, std::pair{&gy, &g.gy}})
      to->assign(from->begin() + first, from->begin() + last);
    window = {z.data(), nx.data(), ny.data(), nz.data(), gx.data(), gy.data(), g.width, g.height};
    window.y0 = y0;
  }
};

TEST_P(SimdTarget, KernelsReadAWindowOfRowsAsTheWholePlanes) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  DenoiseSettings settings;
  const RangeTerms terms = make_range_terms(settings);
  std::size_t lit = 0;
  for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 5}, std::pair{40, 6}, std::pair{33, 3}}) {
    const RandomGuides fine(rng, w, h), coarse(rng, (w + 1) / 2, (h + 1) / 2);
    const UpsampleLight random_light(rng, coarse, w);
    const float* const* coarse_light = random_light.coarse;
    const float* const* own_at = random_light.own_at;
    for (int y = 0; y < h; ++y) {
      // Upsampling to row y, from a window of that row alone.
      std::vector<float> whole(3 * w), windowed(3 * w);
      float* const whole_at[3] = {whole.data(), whole.data() + w, whole.data() + 2 * w};
      float* const windowed_at[3] = {windowed.data(), windowed.data() + w, windowed.data() + 2 * w};
      upsample_row(fine.planes(), y, coarse.planes(), coarse_light, own_at, terms, whole_at);
      upsample_row(RowWindow(fine, y, 1).window, y, coarse.planes(), coarse_light, own_at, terms,
                   windowed_at);
      ASSERT_EQ(std::memcmp(whole.data(), windowed.data(), whole.size() * sizeof(float)), 0)
          << w << "x" << h << " row " << y;
      for (float v : whole) lit += v > 0;
    }
    const int cw = (w + 1) / 2;
    const float* const none[3] = {nullptr, nullptr, nullptr};
    float* const no_light[3] = {nullptr, nullptr, nullptr};
    for (int y = 0; y < (h + 1) / 2; ++y) {
      // Halving rows 2y and 2y + 1, from a window of those two.
      std::vector<float> whole(4 * cw), windowed(4 * cw);
      auto row = [&](std::vector<float>& v) {
        return GuideRow{v.data(), v.data() + cw, v.data() + 2 * cw, v.data() + 3 * cw};
      };
      downsample_row(fine.planes(), none, y, cw, terms, row(whole), no_light);
      downsample_row(RowWindow(fine, 2 * y, 2).window, none, y, cw, terms, row(windowed), no_light);
      ASSERT_EQ(std::memcmp(whole.data(), windowed.data(), whole.size() * sizeof(float)), 0)
          << w << "x" << h << " coarse row " << y;
    }
  }
  EXPECT_GT(lit, 100u);
}

TEST_P(SimdTarget, JointBilateralRowMatchesTheScalarTwinBitForBit) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  std::size_t blended = 0;
  for (auto [w, h] :
       {std::pair{1, 1}, std::pair{5, 3}, std::pair{19, 7}, std::pair{40, 5}, std::pair{26, 1}}) {
    RandomGuides g(rng, w, h);
    for (std::size_t k = 1; k < g.z.size(); ++k)  // runs of one surface, so that taps blend
      if (rng() % 3) g.z[k] = g.z[k - 1], g.nx[k] = g.nx[k - 1], g.ny[k] = g.ny[k - 1];
    const std::size_t n = g.z.size();
    std::vector<float> light(3 * n);
    for (float& v : light) v = u(rng);
    const float* const planes[3] = {light.data(), light.data() + n, light.data() + 2 * n};
    // Every radius, and the normal powers the range weight computes differently (whole ones by
    // squaring, 0, and 7 with its odd bits).
    for (auto [radius, power] :
         {std::pair{0, 32.0f}, std::pair{1, 32.0f}, std::pair{2, 32.0f}, std::pair{3, 32.0f},
          std::pair{2, 1.0f}, std::pair{2, 0.0f}, std::pair{2, 7.0f}}) {
      std::vector<float> taps(radius + 1);
      for (int k = 0; k <= radius; ++k) taps[k] = std::exp(-0.2f * static_cast<float>(k * k));
      DenoiseSettings settings;
      settings.normal_power = power;
      const RangeTerms terms = make_range_terms(settings);
      for (int y = 0; y < h; ++y) {
        std::vector<float> simd(3 * w + 1, -1.0f), scalar(3 * w, -2.0f);
        float* const a[3] = {simd.data(), simd.data() + w, simd.data() + 2 * w};
        float* const b[3] = {scalar.data(), scalar.data() + w, scalar.data() + 2 * w};
        joint_bilateral_row(g.planes(), planes, y, radius, taps.data(), terms, a);
        joint_bilateral_row_scalar(g.planes(), planes, y, radius, taps.data(), terms, b);
        ASSERT_EQ(std::memcmp(simd.data(), scalar.data(), 3 * w * sizeof(float)), 0)
            << w << "x" << h << " row " << y << " radius " << radius << " power " << power;
        EXPECT_EQ(simd[3 * w], -1.0f);
        for (int x = 0; x < w; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * w + x;
          if (!is_surface(g.z[i])) {
            EXPECT_EQ(scalar[x], 0.0f);
            continue;
          }
          EXPECT_TRUE(scalar[x] >= 0.0f && scalar[x] <= 4.0f) << scalar[x];
          blended += std::fabs(scalar[x] - light[i]) > 1e-3f;
        }
      }
    }
  }
  EXPECT_GT(blended, 200u);  // neighbours' light came in
}

TEST_P(SimdTarget, DownsampleRowMatchesTheScalarTwinBitForBit) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  std::size_t mixed = 0;
  for (auto [w, h] : {std::pair{1, 1}, std::pair{2, 2}, std::pair{7, 5}, std::pair{35, 9},
                      std::pair{64, 4}, std::pair{33, 1}}) {
    RandomGuides fine(rng, w, h);
    // Neighbouring samples on one surface now and then, so that blocks blend.
    for (std::size_t k = 1; k < fine.z.size(); k += 2)
      if (rng() % 2) fine.z[k] = fine.z[k - 1], fine.nx[k] = fine.nx[k - 1];
    std::vector<float> light(3 * fine.z.size());
    for (float& v : light) v = u(rng);
    const std::size_t n = fine.z.size();
    const float* const fine_light[3] = {light.data(), light.data() + n, light.data() + 2 * n};
    const float* const no_light[3] = {nullptr, nullptr, nullptr};
    const int cw = (w + 1) / 2;
    for (float power : {32.0f, 2.0f}) {
      DenoiseSettings settings;
      settings.normal_power = power;
      const RangeTerms terms = make_range_terms(settings);
      for (int y = 0; y < (h + 1) / 2; ++y) {
        for (bool with_light : {true, false}) {
          std::vector<float> a(7 * cw + 1, -1.0f), b(7 * cw, -2.0f);
          auto row = [&](std::vector<float>& v) {
            return GuideRow{v.data(), v.data() + cw, v.data() + 2 * cw, v.data() + 3 * cw};
          };
          float* const la[3] = {a.data() + 4 * cw, a.data() + 5 * cw, a.data() + 6 * cw};
          float* const lb[3] = {b.data() + 4 * cw, b.data() + 5 * cw, b.data() + 6 * cw};
          float* const none[3] = {nullptr, nullptr, nullptr};
          downsample_row(fine.planes(), with_light ? fine_light : no_light, y, cw, terms, row(a),
                         with_light ? la : none);
          downsample_row_scalar(fine.planes(), with_light ? fine_light : no_light, y, cw, terms,
                                row(b), with_light ? lb : none);
          const std::size_t written = (with_light ? 7 : 4) * static_cast<std::size_t>(cw);
          ASSERT_EQ(std::memcmp(a.data(), b.data(), written * sizeof(float)), 0)
              << w << "x" << h << " row " << y << " light " << with_light;
          EXPECT_EQ(a[7 * cw], -1.0f);
          if (!with_light) continue;
          for (int x = 0; x < cw; ++x) {
            const float v = lb[0][x];
            EXPECT_TRUE(v >= 0.0f && v <= 4.0f) << v;
            // A blend of two or more samples, not one sample's value.
            bool one_sample = false;
            for (int k = 0; k < 4; ++k) {
              const int fx = 2 * x + (k & 1), fy = 2 * y + (k >> 1);
              if (fx < w && fy < h) one_sample |= v == fine_light[0][fy * w + fx];
            }
            mixed += !one_sample && is_surface(b[x]);
          }
        }
      }
    }
  }
  EXPECT_GT(mixed, 50u);
}

TEST_P(SimdTarget, DepthGradientRowMatchesTheScalarTwinBitForBit) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::size_t sloped = 0;
  for (auto [w, h] : {std::pair{1, 1}, std::pair{3, 2}, std::pair{11, 7}, std::pair{13, 1},
                      std::pair{1, 13}, std::pair{64, 9}}) {
    // Planes with depth edges, ridges, background and depths far apart.
    std::vector<float> z(static_cast<std::size_t>(w) * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float v = 2.0f + 0.1f * static_cast<float>(x) - 0.05f * static_cast<float>(y);
        const float r = u(rng);
        if (r < 0.1f)
          v = kInf;
        else if (r < 0.2f)
          v *= 3.0f;
        else if (r < 0.25f)
          v = 1e30f;
        z[static_cast<std::size_t>(y) * w + x] = v;
      }
    for (int y = 0; y < h; ++y) {
      std::vector<float> sx(w + 1, -1.0f), sy(w + 1, -1.0f), tx(w), ty(w);
      depth_gradient_row(z.data(), w, h, y, sx.data(), sy.data());
      depth_gradient_row_scalar(z.data(), w, h, y, tx.data(), ty.data());
      ASSERT_EQ(std::memcmp(sx.data(), tx.data(), w * sizeof(float)), 0)
          << w << "x" << h << " " << y;
      ASSERT_EQ(std::memcmp(sy.data(), ty.data(), w * sizeof(float)), 0)
          << w << "x" << h << " " << y;
      EXPECT_EQ(sx[w], -1.0f);
      for (int x = 0; x < w; ++x) sloped += std::fabs(tx[x] - 0.1f) < 1e-4f;
    }
  }
  EXPECT_GT(sloped, 100u);  // the planes' own slope found along x
}

// A random slice frame: origin, view vector, a direction t across it, the normal at gamma.
SliceFrame random_frame(std::mt19937& rng, float oz) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const float gamma = 1.5f * u(rng);
  const float ox = u(rng), oy = u(rng);
  const float len = std::sqrt(ox * ox + oy * oy + oz * oz);
  const float vx = -ox / len, vy = -oy / len, vz = -oz / len;
  float tx = vz, ty = 0, tz = -vx;  // any unit vector across v
  const float tl = std::sqrt(tx * tx + tz * tz);
  tx /= tl, tz /= tl;
  const float cg = std::cos(gamma), sg = std::sin(gamma);
  const float lo = gamma - 0.5f * kSlicePi, hi = gamma + 0.5f * kSlicePi;
  // The slice's measure at the hemisphere's bounds (slices.cpp's SliceMeasure), so that the
  // coordinates run over the 32 sectors.
  auto measure = [&](float theta, float sn, float cs) {
    const float g = 0.5f * (cg * sn * sn + sg * (theta - sn * cs));
    return sn < 0 ? -g : g;
  };
  const float h_lo = measure(lo, -cg, sg), h_hi = measure(hi, cg, -sg);
  return {ox,
          oy,
          oz,
          vx,
          vy,
          vz,
          tx,
          ty,
          tz,
          cg,
          sg,
          lo,
          hi,
          h_lo,
          32.0f / (h_hi - h_lo),
          0.5f * (u(rng) + 1.0f)};
}

// A mesh of w x h texels: a tilted plane in front of the slices' origins with steps, holes
// (background, no triangles), random triangle flags, normals and slab thicknesses (a third at
// the model's, the rest thin features).
std::vector<MeshTexel> random_mesh(std::mt19937& rng, int w, int h) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 15), normal(-127, 127);
  std::vector<MeshTexel> texels(static_cast<std::size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      MeshTexel& t = texels[static_cast<std::size_t>(j) * w + i];
      float z = 4.0f + 0.05f * static_cast<float>(i) - 0.03f * static_cast<float>(j);
      if (pick(rng) == 0) z *= 1.5f;  // a depth step
      t.inverse_depth = pick(rng) == 1 ? 0.0f : 1.0f / z;
      t.nx = static_cast<std::int8_t>(normal(rng));
      t.ny = static_cast<std::int8_t>(normal(rng));
      t.nz = static_cast<std::int8_t>(-std::abs(normal(rng)));
      t.triangles = t.inverse_depth == 0 ? 0 : static_cast<std::uint8_t>(pick(rng) % 4);
      if (pick(rng) < 10) t.triangles = kUpperTriangle | kLowerTriangle;
      if (pick(rng) > 4)
        t.triangles |= static_cast<std::uint8_t>(thickness_code(u(rng) * u(rng) * 0.1f, 0.1f)
                                                 << kThicknessShift);
    }
  return texels;
}

TEST_P(SimdTarget, MarchSideMatchesTheScalarTwinBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::size_t bits_set = 0, bridged = 0, samples = 0, bounded_backs = 0;
  for (auto [w, h] :
       {std::pair{37, 23}, std::pair{64, 64}, std::pair{1, 9}, std::pair{9, 1}, std::pair{2, 2}}) {
    const std::vector<MeshTexel> texels = random_mesh(rng, w, h);
    const MeshView mesh{texels.data(), w, h};
    for (int trial = 0; trial < 60; ++trial) {
      const SliceFrame f = random_frame(rng, 5.0f + u(rng));  // among the mesh's depths
      const float angle = kSlicePi * u(rng);
      SideMarch m{};
      m.qx = 0.5f * static_cast<float>(w) * (1.0f + u(rng));
      m.qy = 0.5f * static_cast<float>(h) * (1.0f + u(rng));
      m.sx = std::cos(angle), m.sy = std::sin(angle);
      m.t_max = 1.0f + static_cast<float>(std::max(w, h)) * (1.0f + u(rng));
      m.u_step = 0.5f * (1.0f + u(rng));
      m.cx = 0.5f * static_cast<float>(w), m.cy = 0.5f * static_cast<float>(h);
      m.inv_fx = m.inv_fy = 1.0f / static_cast<float>(std::max(w, h));
      m.thickness = 0.1f;
      m.max_distance2 = trial % 3 == 0 ? 0.3f * (1.0f + u(rng)) : 0.0f;
      for (int steps : {1, 7, 8, 9, 16, 28, 33}) {
        m.steps = steps;
        SideSamples simd, scalar;
        const int n_simd = march_side(mesh, f, m, &simd);
        const int n_scalar = march_side_scalar(mesh, f, m, &scalar);
        ASSERT_EQ(n_simd, n_scalar) << w << "x" << h << " trial " << trial << " steps " << steps;
        ASSERT_EQ(simd.beyond_above, scalar.beyond_above) << trial << " " << steps;
        ASSERT_EQ(simd.beyond_below, scalar.beyond_below) << trial << " " << steps;
        bounded_backs += std::isfinite(scalar.beyond_above) + std::isfinite(scalar.beyond_below);
        for (int j = 0; j < n_scalar; ++j) {
          ASSERT_EQ(simd.pixel[j + 1], scalar.pixel[j + 1]) << trial << " " << steps << " " << j;
          ASSERT_EQ(simd.bits[j], scalar.bits[j]) << trial << " " << steps << " " << j;
          // A vertex's own slab, which the missed rays read (where they pass behind it).
          if (scalar.pixel[j + 1] >= 0) {
            ASSERT_EQ(simd.front_u[j + 1], scalar.front_u[j + 1]) << trial << " " << j;
            ASSERT_EQ(simd.back_u[j + 1], scalar.back_u[j + 1]) << trial << " " << j;
          }
          samples += scalar.pixel[j + 1] >= 0;
          bits_set += scalar.bits[j] != 0;
          // Consecutive samples: where the kernel decides whether to bridge.
          if (j > 0 && scalar.pixel[j] >= 0 && scalar.pixel[j + 1] >= 0) ++bridged;
        }
      }
    }
  }
  // Not a trivial run: samples met the mesh, shadowed sectors, and followed each other.
  EXPECT_GT(samples, 2000u);
  EXPECT_GT(bits_set, 1000u);
  EXPECT_GT(bridged, 500u);
  EXPECT_GT(bounded_backs, 300u);
}

TEST_P(SimdTarget, CollectHitsMatchesTheScalarTwinBitForBit) {
  std::mt19937 rng(13);
  std::uniform_int_distribution<std::uint32_t> word;
  std::uniform_int_distribution<int> pick(0, 3);
  std::size_t hits = 0, saturated = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int count = trial % 38;  // every length up to past a side's usual 28 steps
    SideSamples samples;
    samples.reserve(count);
    for (int j = 0; j < count; ++j) {
      // Sparse, dense, empty and full words, as a side's samples bring.
      const std::uint32_t r = word(rng);
      const std::uint32_t kinds[4] = {r & word(rng) & word(rng), r, 0u, ~0u};
      samples.bits[j] = kinds[pick(rng)];
      samples.pixel[j + 1] = static_cast<std::int32_t>(word(rng) >> 1);
    }
    const std::uint32_t start = trial % 5 == 0 ? 0u : word(rng) & word(rng);
    const float sector_weight = 1e-3f * static_cast<float>(1 + trial);
    std::vector<std::int32_t> pixel_simd(count + 1), pixel_scalar(count + 1);
    std::vector<float> weight_simd(count + 1), weight_scalar(count + 1);
    std::uint32_t mask_simd = start, mask_scalar = start;
    const int kept_simd = collect_hits(samples, count, sector_weight, &mask_simd, pixel_simd.data(),
                                       weight_simd.data());
    const int kept_scalar = collect_hits_scalar(samples, count, sector_weight, &mask_scalar,
                                                pixel_scalar.data(), weight_scalar.data());
    ASSERT_EQ(kept_simd, kept_scalar) << trial;
    ASSERT_EQ(mask_simd, mask_scalar) << trial;
    std::uint32_t mask = start;
    float total = 0;
    for (int k = 0; k < kept_scalar; ++k) {
      ASSERT_EQ(pixel_simd[k], pixel_scalar[k]) << trial << " " << k;
      ASSERT_EQ(weight_simd[k], weight_scalar[k]) << trial << " " << k;
      total += weight_scalar[k];
    }
    // Each sector is counted once: the hits' weights are the sectors the side added.
    for (int j = 0; j < count; ++j) mask |= samples.bits[j];
    EXPECT_EQ(mask_scalar, mask);
    EXPECT_NEAR(total, sector_weight * static_cast<float>(sector_count(mask & ~start)),
                1e-5f * (1 + trial));
    hits += static_cast<std::size_t>(kept_scalar);
    saturated += mask == ~0u;
  }
  EXPECT_GT(hits, 500u);
  EXPECT_GT(saturated, 50u);
}

TEST(Simd, SectorBitsAreTheSectorsInsideTheInterval) {
  EXPECT_EQ(sector_bits(-0.5f, 0.5f), 1u);          // sector 0
  EXPECT_EQ(sector_bits(0.5f, 3.0f), 0b1110u);      // 1, 2, 3
  EXPECT_EQ(sector_bits(-10.0f, 40.0f), ~0u);       // all, clamped
  EXPECT_EQ(sector_bits(30.2f, 31.0f), 1u << 31);   // the last
  EXPECT_EQ(sector_bits(0.2f, 0.8f), 0u);           // between two sectors
  EXPECT_EQ(sector_bits(3.0f, 2.0f), 0u);           // empty
  EXPECT_EQ(sector_bits(31.5f, 40.0f), 0u);         // beyond the last
  EXPECT_EQ(sector_bits(std::nanf(""), 4.0f), 0u);  // not a number
  EXPECT_EQ(sector_bits(-1e30f, 1e30f), ~0u);
}

TEST(Simd, SectorCoordinatesSpanTheHemisphere) {
  // The coordinates span the hemisphere (here around the view vector): towards the camera is
  // its middle (half the measure), along t and against it its edges, and beyond them clamps.
  const SliceFrame f{0,     0,     3,    0, 0, -1, 1, 0, 0, 1, 0, -0.5f * kSlicePi, 0.5f * kSlicePi,
                     -0.5f, 32.0f, 0.25f};
  EXPECT_NEAR(sector_coordinate(f, 0, 0, -1), 16.0f - 0.25f, 1e-4);  // towards the camera
  EXPECT_NEAR(sector_coordinate(f, 1, 0, 0), 32.0f - 0.25f, 1e-4);   // along t
  EXPECT_NEAR(sector_coordinate(f, -1, 0, 0), 0.0f - 0.25f, 1e-4);   // against t
  EXPECT_NEAR(sector_coordinate(f, 0, 0, 1), 32.0f - 0.25f, 1e-4);   // behind: clamped
}

INSTANTIATE_TEST_SUITE_P(EveryTarget, SimdTarget, ::testing::ValuesIn(pinned_targets()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
}  // namespace ssgi::detail
