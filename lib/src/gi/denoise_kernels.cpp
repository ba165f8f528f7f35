// The denoiser's kernels, compiled once per SIMD target (Highway's foreach_target).
#include "gi/denoise_kernels.h"

#include <cstdlib>
#include <string>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "gi/denoise_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace ssgi {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// range_weight (denoise_kernels.h) on lanes, operation for operation: the constants once per
// call, the weight per vector of pairs.
template <class D>
struct RangeWeightV {
  using V = hn::Vec<D>;
  D d;
  hn::RebindToSigned<D> di;
  int power;
  V zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  V inv_sigma, max_exponent = hn::Set(d, kMaxExponent), log2e = hn::Set(d, 1.44269504f);
  V c1 = hn::Set(d, 0.6931472f), c2 = hn::Set(d, 0.2402265f), c3 = hn::Set(d, 0.05550357f),
    c4 = hn::Set(d, 0.009618129f), c5 = hn::Set(d, 0.001333355f), c6 = hn::Set(d, 0.0001540353f);

  explicit RangeWeightV(const RangeTerms& terms)
      : power(terms.integer_normal_power), inv_sigma(hn::Set(d, terms.inv_sigma_depth)) {}

  // The depth test's factor of a pixel at depth pz: inv_sigma / pz.
  V scale(V pz) const { return hn::Div(inv_sigma, pz); }

  V operator()(V pz, V pnx, V pny, V pnz, V pgx, V pgy, V qz, V qnx, V qny, V qnz, V dx,
               V dy) const {
    return weigh(scale(pz), pz, pnx, pny, pnz, pgx, pgy, qz, qnx, qny, qnz, dx, dy);
  }

  // With the pixel's factor computed once (`scale`).
  V weigh(V p_scale, V pz, V pnx, V pny, V pnz, V pgx, V pgy, V qz, V qnx, V qny, V qnz, V dx,
          V dy) const {
    const V dz = hn::Sub(hn::Sub(hn::Sub(qz, pz), hn::Mul(pgx, dx)), hn::Mul(pgy, dy));
    const V s = hn::Mul(dz, p_scale);
    const V exponent = hn::Mul(hn::Mul(half, s), s);
    const auto valid = hn::Lt(exponent, max_exponent);
    // exp_negative
    const V t = hn::Mul(hn::Neg(exponent), log2e);
    const V whole = hn::Floor(t);
    const V f = hn::Sub(t, whole);
    V poly = hn::Add(c5, hn::Mul(f, c6));
    poly = hn::Add(c4, hn::Mul(f, poly));
    poly = hn::Add(c3, hn::Mul(f, poly));
    poly = hn::Add(c2, hn::Mul(f, poly));
    poly = hn::Add(c1, hn::Mul(f, poly));
    poly = hn::Add(one, hn::Mul(f, poly));
    // Lanes past the cut-off (or NaN) are zeroed below; their exponent is not converted, since
    // converting NaN or a huge value to an integer is undefined (Highway's emulated targets
    // use a C++ cast).
    const V scale =
        hn::BitCast(d, hn::ShiftLeft<23>(hn::Add(
                           hn::ConvertTo(di, hn::IfThenElseZero(valid, whole)), hn::Set(di, 127))));
    V w = hn::Mul(poly, scale);
    // The normal term.
    const V cos_angle = hn::Add(hn::Add(hn::Mul(pnx, qnx), hn::Mul(pny, qny)), hn::Mul(pnz, qnz));
    V x = hn::Min(cos_angle, one);
    V term = one;
    for (int p = power; p > 0; p >>= 1, x = hn::Mul(x, x))
      if (p & 1) term = hn::Mul(term, x);
    const auto facing = hn::Gt(cos_angle, zero);
    const auto p_normal = hn::Or(hn::Or(hn::Ne(pnx, zero), hn::Ne(pny, zero)), hn::Ne(pnz, zero));
    const auto q_normal = hn::Or(hn::Or(hn::Ne(qnx, zero), hn::Ne(qny, zero)), hn::Ne(qnz, zero));
    w = hn::IfThenElse(facing, hn::Mul(w, term),
                       hn::IfThenZeroElse(hn::And(p_normal, q_normal), w));
    return hn::IfThenElseZero(valid, w);
  }
};

// axis_gradient on lanes.
template <class D, class V = hn::Vec<D>>
V AxisGradient(D d, V before2, V before1, V z0, V after1, V after2) {
  const V zero = hn::Zero(d);
  auto agreeing = [&](V a, V b, auto* ok) {
    *ok = hn::And(hn::IsFinite(a), hn::IsFinite(b));
    const auto opposite = hn::Or(hn::And(hn::Lt(a, zero), hn::Gt(b, zero)),
                                 hn::And(hn::Gt(a, zero), hn::Lt(b, zero)));
    return hn::IfThenZeroElse(opposite, hn::IfThenElse(hn::Le(hn::Abs(a), hn::Abs(b)), a, b));
  };
  const V before = hn::Sub(z0, before1), after = hn::Sub(after1, z0);
  hn::Mask<D> ok1, ok2, ok3;
  const V g1 = agreeing(before, after, &ok1);
  const V g2 = agreeing(after, hn::Sub(after2, after1), &ok2);
  const V g3 = agreeing(hn::Sub(before1, before2), before, &ok3);
  return hn::IfThenElse(ok1, g1, hn::IfThenElse(ok2, g2, hn::IfThenElseZero(ok3, g3)));
}

void DepthGradientRow(const float* z, int w, int h, int y, float* gx, float* gy) {
  const hn::ScalableTag<float> d;
  using V = hn::Vec<decltype(d)>;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const V inf = hn::Set(d, kInf);
  // The rows two above to two below, null outside the image.
  const float* rows[5];
  for (int k = -2; k <= 2; ++k)
    rows[k + 2] = y + k >= 0 && y + k < h ? z + static_cast<std::size_t>(y + k) * w : nullptr;
  const float* row = rows[2];
  int x = 0;
  for (; x < std::min(2, w); ++x) depth_gradient_pixel(z, w, h, x, y, gx, gy);
  for (; x + lanes + 2 <= w; x += lanes) {
    auto at = [&](int k) { return rows[k + 2] ? hn::LoadU(d, rows[k + 2] + x) : inf; };
    const V z0 = hn::LoadU(d, row + x);
    const auto surface = hn::Lt(z0, inf);
    const V grad_x = AxisGradient(d, hn::LoadU(d, row + x - 2), hn::LoadU(d, row + x - 1), z0,
                                  hn::LoadU(d, row + x + 1), hn::LoadU(d, row + x + 2));
    const V grad_y = AxisGradient(d, at(-2), at(-1), z0, at(1), at(2));
    hn::StoreU(hn::IfThenElseZero(surface, grad_x), d, gx + x);
    hn::StoreU(hn::IfThenElseZero(surface, grad_y), d, gy + x);
  }
  for (; x < w; ++x) depth_gradient_pixel(z, w, h, x, y, gx, gy);
}

void JointBilateralRowSimd(const GuidePlanes& g, const float* const light[3], int y, int radius,
                           const float* taps, const RangeTerms& terms, float* const out[3]) {
  const hn::ScalableTag<float> d;
  using VF = hn::Vec<decltype(d)>;
  const RangeWeightV<decltype(d)> weight(terms);
  const int w = g.width, lanes = static_cast<int>(hn::Lanes(d));
  const std::size_t row = static_cast<std::size_t>(y) * w;
  const VF zero = hn::Zero(d), inf = hn::Set(d, kInf);
  const int y0 = std::max(0, y - radius), y1 = std::min(g.height - 1, y + radius);
  int x0 = 0;
  for (; x0 < std::min(radius, w); ++x0)
    joint_bilateral_pixel(g, light, x0, y, radius, taps, terms, out);
  // Whole vectors whose windows lie inside the row.
  for (; x0 + lanes + radius <= w; x0 += lanes) {
    const std::size_t i = row + static_cast<std::size_t>(x0);
    const VF pz = hn::LoadU(d, g.z + i), pnx = hn::LoadU(d, g.nx + i), pny = hn::LoadU(d, g.ny + i),
             pnz = hn::LoadU(d, g.nz + i), pgx = hn::LoadU(d, g.gx + i),
             pgy = hn::LoadU(d, g.gy + i);
    const VF p_scale = weight.scale(pz);
    VF weight_sum = zero, sum[3] = {zero, zero, zero}, lo[3] = {inf, inf, inf}, hi[3];
    for (int c = 0; c < 3; ++c) hi[c] = hn::Neg(inf);
    for (int qy = y0; qy <= y1; ++qy) {
      for (int dx = -radius; dx <= radius; ++dx) {
        const std::size_t j = static_cast<std::size_t>(qy) * w + x0 + dx;
        const float spatial = taps[std::abs(dx)] * taps[std::abs(qy - y)];
        const VF range =
            qy == y && dx == 0
                ? hn::Set(d, 1.0f)
                : weight.weigh(p_scale, pz, pnx, pny, pnz, pgx, pgy, hn::LoadU(d, g.z + j),
                               hn::LoadU(d, g.nx + j), hn::LoadU(d, g.ny + j),
                               hn::LoadU(d, g.nz + j), hn::Set(d, static_cast<float>(dx)),
                               hn::Set(d, static_cast<float>(qy - y)));
        const VF wq = hn::Mul(hn::Set(d, spatial), range);
        const auto counts = hn::Gt(wq, zero);
        weight_sum = hn::Add(weight_sum, wq);
        for (int c = 0; c < 3; ++c) {
          const VF v = hn::LoadU(d, light[c] + j);
          sum[c] = hn::Add(sum[c], hn::IfThenElseZero(counts, hn::Mul(wq, v)));
          lo[c] = hn::IfThenElse(counts, hn::Min(lo[c], v), lo[c]);
          hi[c] = hn::IfThenElse(counts, hn::Max(hi[c], v), hi[c]);
        }
      }
    }
    const auto surface = hn::Lt(pz, inf);
    for (int c = 0; c < 3; ++c)
      hn::StoreU(
          hn::IfThenElseZero(surface, hn::Min(hn::Max(hn::Div(sum[c], weight_sum), lo[c]), hi[c])),
          d, out[c] + x0);
  }
  for (; x0 < w; ++x0) joint_bilateral_pixel(g, light, x0, y, radius, taps, terms, out);
}

void DownsampleRowSimd(const GuidePlanes& fine, const float* const fine_light[3], int y,
                       int coarse_width, const RangeTerms& terms, const GuideRow& out,
                       float* const light_out[3]) {
  const hn::ScalableTag<float> d;
  using VF = hn::Vec<decltype(d)>;
  using M = hn::Mask<decltype(d)>;
  const RangeWeightV<decltype(d)> weight(terms);
  const int lanes = static_cast<int>(hn::Lanes(d));
  const bool with_light = fine_light[0] != nullptr;
  const VF inf = hn::Set(d, kInf), zero = hn::Zero(d), half = hn::Set(d, 0.5f);
  const VF one = hn::Set(d, 1.0f);
  // The block's two fine rows (the second missing below the last row).
  const std::size_t rows[2] = {fine.index(0, 2 * y), fine.index(0, 2 * y + 1)};
  const bool second_row = 2 * y + 1 < fine.height;
  const float centre_y = 2.0f * static_cast<float>(y) + 0.5f;
  int x0 = 0;
  // Whole vectors where every block has both its columns.
  for (; x0 + lanes <= coarse_width && 2 * (x0 + lanes) <= fine.width; x0 += lanes) {
    // Sample k of every lane's block: k & 1 its column, k >> 1 its row.
    VF z[4], nx[4], ny[4], nz[4], gx[4], gy[4], light[3][4];
    auto load = [&](const float* plane, VF* v, VF missing) {
      for (int r = 0; r < 2; ++r) {
        if (r == 1 && !second_row) {
          v[2] = v[3] = missing;
          continue;
        }
        hn::LoadInterleaved2(d, plane + rows[r] + 2 * x0, v[2 * r], v[2 * r + 1]);
      }
    };
    load(fine.z, z, inf);
    load(fine.nx, nx, zero), load(fine.ny, ny, zero), load(fine.nz, nz, zero);
    load(fine.gx, gx, zero), load(fine.gy, gy, zero);
    if (with_light)
      for (int c = 0; c < 3; ++c) load(fine_light[c], light[c], zero);
    M surface[4];
    VF count = zero;
    for (int k = 0; k < 4; ++k) {
      surface[k] = hn::Lt(z[k], inf);
      count = hn::Add(count, hn::IfThenElseZero(surface[k], one));
    }
    // The median of the surface depths (anything else sorts last as +inf).
    VF zs[4];
    for (int k = 0; k < 4; ++k) zs[k] = hn::IfThenElse(surface[k], z[k], inf);
    VF s0 = hn::Min(zs[0], zs[1]), s1 = hn::Max(zs[0], zs[1]);
    VF s2 = hn::Min(zs[2], zs[3]), s3 = hn::Max(zs[2], zs[3]);
    VF t = hn::Min(s0, s2);
    s2 = hn::Max(s0, s2), s0 = t;
    t = hn::Min(s1, s3);
    s3 = hn::Max(s1, s3), s1 = t;
    t = hn::Min(s1, s2);
    s2 = hn::Max(s1, s2), s1 = t;
    const VF mean01 = hn::Add(hn::Mul(half, s0), hn::Mul(half, s1));
    const VF mean12 = hn::Add(hn::Mul(half, s1), hn::Mul(half, s2));
    const VF median =
        hn::IfThenElse(hn::Eq(count, one), s0,
                       hn::IfThenElse(hn::Eq(count, hn::Set(d, 2.0f)), mean01,
                                      hn::IfThenElse(hn::Eq(count, hn::Set(d, 3.0f)), s1, mean12)));
    // The representative, in the scalar twin's order.
    M have = hn::FirstN(d, 0);
    VF best_z = zero, best_d = zero, rz = zero, rnx = zero, rny = zero, rnz = zero, rgx = zero,
       rgy = zero, r_index = zero;
    for (int k = 0; k < 4; ++k) {
      const VF dist = hn::Abs(hn::Sub(z[k], median));
      const M better = hn::And(
          surface[k],
          hn::Or(hn::Not(have), hn::Or(hn::Lt(dist, best_d),
                                       hn::And(hn::Eq(dist, best_d), hn::Lt(z[k], best_z)))));
      best_z = hn::IfThenElse(better, z[k], best_z);
      best_d = hn::IfThenElse(better, dist, best_d);
      rz = hn::IfThenElse(better, z[k], rz);
      rnx = hn::IfThenElse(better, nx[k], rnx);
      rny = hn::IfThenElse(better, ny[k], rny);
      rnz = hn::IfThenElse(better, nz[k], rnz);
      rgx = hn::IfThenElse(better, gx[k], rgx);
      rgy = hn::IfThenElse(better, gy[k], rgy);
      r_index = hn::IfThenElse(better, hn::Set(d, static_cast<float>(k)), r_index);
      have = hn::Or(have, surface[k]);
    }
    // The representative's column and row in its block.
    const VF r_row = hn::IfThenElse(hn::Ge(r_index, hn::Set(d, 2.0f)), one, zero);
    const VF r_column = hn::Sub(r_index, hn::Add(r_row, r_row));
    const VF x_block =
        hn::Mul(hn::Set(d, 2.0f), hn::Add(hn::Iota(d, 0.0f), hn::Set(d, static_cast<float>(x0))));
    const VF centre_x = hn::Add(x_block, half);
    VF weight_sum = zero, sz = zero, snx = zero, sny = zero, snz = zero;
    VF sl[3] = {zero, zero, zero}, lo[3] = {inf, inf, inf}, hi[3];
    for (int c = 0; c < 3; ++c) hi[c] = hn::Neg(inf);
    const VF r_scale = weight.scale(rz);
    for (int k = 0; k < 4; ++k) {
      const float bx = static_cast<float>(k & 1), by = static_cast<float>(k >> 1);
      const VF range =
          weight.weigh(r_scale, rz, rnx, rny, rnz, rgx, rgy, z[k], nx[k], ny[k], nz[k],
                       hn::Sub(hn::Set(d, bx), r_column), hn::Sub(hn::Set(d, by), r_row));
      const VF wq = hn::IfThenElseZero(
          surface[k],
          hn::IfThenElse(hn::Eq(r_index, hn::Set(d, static_cast<float>(k))), one, range));
      const M counts = hn::Gt(wq, zero);
      weight_sum = hn::Add(weight_sum, wq);
      const VF sx = hn::Add(x_block, hn::Set(d, bx));
      const VF sy = hn::Set(d, static_cast<float>(2 * y) + by);
      const VF moved = hn::Add(hn::Add(z[k], hn::Mul(rgx, hn::Sub(centre_x, sx))),
                               hn::Mul(rgy, hn::Sub(hn::Set(d, centre_y), sy)));
      sz = hn::Add(sz, hn::IfThenElseZero(counts, hn::Mul(wq, moved)));
      snx = hn::Add(snx, hn::IfThenElseZero(counts, hn::Mul(wq, nx[k])));
      sny = hn::Add(sny, hn::IfThenElseZero(counts, hn::Mul(wq, ny[k])));
      snz = hn::Add(snz, hn::IfThenElseZero(counts, hn::Mul(wq, nz[k])));
      if (with_light)
        for (int c = 0; c < 3; ++c) {
          const VF v = light[c][k];
          sl[c] = hn::Add(sl[c], hn::IfThenElseZero(counts, hn::Mul(wq, v)));
          lo[c] = hn::IfThenElse(counts, hn::Min(lo[c], v), lo[c]);
          hi[c] = hn::IfThenElse(counts, hn::Max(hi[c], v), hi[c]);
        }
    }
    const M any = hn::Gt(count, zero);
    // Background lanes divide by 0 here; their results are replaced below.
    const VF zm = hn::Div(sz, weight_sum);
    const VF out_z = hn::IfThenElse(hn::And(hn::Gt(zm, zero), hn::Lt(zm, inf)), zm, rz);
    hn::StoreU(hn::IfThenElse(any, out_z, inf), d, out.z + x0);
    const VF length =
        hn::Sqrt(hn::Add(hn::Add(hn::Mul(snx, snx), hn::Mul(sny, sny)), hn::Mul(snz, snz)));
    const M normal = hn::And(any, hn::And(hn::Gt(length, zero), hn::Lt(length, inf)));
    hn::StoreU(hn::IfThenElseZero(normal, hn::Div(snx, length)), d, out.nx + x0);
    hn::StoreU(hn::IfThenElseZero(normal, hn::Div(sny, length)), d, out.ny + x0);
    hn::StoreU(hn::IfThenElseZero(normal, hn::Div(snz, length)), d, out.nz + x0);
    if (with_light)
      for (int c = 0; c < 3; ++c)
        hn::StoreU(
            hn::IfThenElseZero(any, hn::Min(hn::Max(hn::Div(sl[c], weight_sum), lo[c]), hi[c])), d,
            light_out[c] + x0);
  }
  for (; x0 < coarse_width; ++x0) downsample_pixel(fine, fine_light, x0, y, terms, out, light_out);
}

void UpsampleRowSimd(const GuidePlanes& fine, int y, const GuidePlanes& coarse,
                     const float* const coarse_light[3], const float* const own[3],
                     const RangeTerms& terms, float* const out[3]) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  using VF = hn::Vec<decltype(d)>;
  const RangeWeightV<decltype(d)> weight(terms);
  const int w = fine.width, lanes = static_cast<int>(hn::Lanes(d));
  const std::size_t row = fine.index(0, y);
  // Along y the row's two coarse rows and their weights (as in upsample_pixel).
  const int first_y = y % 2 == 0 ? y / 2 - 1 : y / 2;
  const float second_wy = y % 2 == 0 ? 0.75f : 0.25f;
  const int cy[2] = {std::clamp(first_y, 0, coarse.height - 1),
                     std::clamp(first_y + 1, 0, coarse.height - 1)};
  const float wy[2] = {1.0f - second_wy, second_wy};
  // Lanes of fine pixels x0 .. x0 + lanes - 1 (x0 even) read the coarse columns x0/2 - 1 + k
  // for k = (lane + 1) / 2 (the first tap) and one more (the second): one load of coarse
  // columns from x0/2 - 1 and a permutation each, where all of those columns exist.
  const auto first_tap =
      hn::IndicesFromVec(d, hn::ShiftRight<1>(hn::Add(hn::Iota(di, 0), hn::Set(di, 1))));
  const auto second_tap = hn::IndicesFromVec(
      d, hn::Add(hn::ShiftRight<1>(hn::Add(hn::Iota(di, 0), hn::Set(di, 1))), hn::Set(di, 1)));
  // The bilinear weights of the two taps alternate with the lanes (x0 even): 1/4 and 3/4 for
  // even x, 3/4 and 1/4 for odd.
  const auto odd =
      hn::RebindMask(d, hn::Ne(hn::And(hn::Iota(di, 0), hn::Set(di, 1)), hn::Zero(di)));
  const VF quarter = hn::Set(d, 0.25f), three_quarters = hn::Set(d, 0.75f);
  const VF wx[2] = {hn::IfThenElse(odd, three_quarters, quarter),
                    hn::IfThenElse(odd, quarter, three_quarters)};
  // dx = (2 cx - x) + 1/2, 2 cx - x being -2 for even x and -1 for odd at the first tap, 2 more
  // at the second.
  const VF dx_first =
      hn::Add(hn::ConvertTo(d, hn::Sub(hn::And(hn::Iota(di, 0), hn::Set(di, 1)), hn::Set(di, 2))),
              hn::Set(d, 0.5f));
  const VF dx[2] = {dx_first, hn::Add(dx_first, hn::Set(d, 2.0f))};
  int x0 = 0;
  for (; x0 < std::min(2, w); ++x0)
    upsample_pixel(fine, x0, y, coarse, coarse_light, own, terms, out);
  for (; lanes >= 4 && x0 + lanes <= w && x0 / 2 - 1 + lanes <= coarse.width; x0 += lanes) {
    const std::size_t i = row + static_cast<std::size_t>(x0);
    const VF pz = hn::LoadU(d, fine.z + i), pnx = hn::LoadU(d, fine.nx + i),
             pny = hn::LoadU(d, fine.ny + i), pnz = hn::LoadU(d, fine.nz + i),
             pgx = hn::LoadU(d, fine.gx + i), pgy = hn::LoadU(d, fine.gy + i);
    const VF p_scale = weight.scale(pz);
    // The four taps' weights first, then the light channel by channel (fewer live registers).
    VF wq[4], sum = hn::Set(d, kOwnValueWeight);
    std::size_t base[2];
    for (int ky = 0; ky < 2; ++ky) {
      base[ky] = static_cast<std::size_t>(cy[ky]) * coarse.width + x0 / 2 - 1;
      const VF dy = hn::Set(d, static_cast<float>(2 * cy[ky] - y) + 0.5f);
      const VF qz = hn::LoadU(d, coarse.z + base[ky]), qnx = hn::LoadU(d, coarse.nx + base[ky]),
               qny = hn::LoadU(d, coarse.ny + base[ky]), qnz = hn::LoadU(d, coarse.nz + base[ky]);
      for (int kx = 0; kx < 2; ++kx) {
        const auto& tap = kx ? second_tap : first_tap;
        const VF range =
            weight.weigh(p_scale, pz, pnx, pny, pnz, pgx, pgy, hn::TableLookupLanes(qz, tap),
                         hn::TableLookupLanes(qnx, tap), hn::TableLookupLanes(qny, tap),
                         hn::TableLookupLanes(qnz, tap), dx[kx], dy);
        VF& q = wq[2 * ky + kx];
        q = hn::Mul(hn::Mul(wx[kx], hn::Set(d, wy[ky])), range);
        sum = hn::Add(sum, q);
      }
    }
    const auto surface = hn::Lt(pz, hn::Set(d, kInf));
    for (int c = 0; c < 3; ++c) {
      const VF own_light = hn::LoadU(d, own[c] + x0);
      VF light = hn::Mul(hn::Set(d, kOwnValueWeight), own_light), lo = own_light, hi = own_light;
      for (int ky = 0; ky < 2; ++ky) {
        const VF ql = hn::LoadU(d, coarse_light[c] + base[ky]);
        for (int kx = 0; kx < 2; ++kx) {
          const VF v = hn::TableLookupLanes(ql, kx ? second_tap : first_tap);
          const VF q = wq[2 * ky + kx];
          light = hn::Add(light, hn::Mul(q, v));
          const VF counted = hn::IfThenElse(hn::Gt(q, hn::Zero(d)), v, own_light);
          lo = hn::Min(lo, counted), hi = hn::Max(hi, counted);
        }
      }
      hn::StoreU(hn::IfThenElseZero(surface, hn::Min(hn::Max(hn::Div(light, sum), lo), hi)), d,
                 out[c] + x0);
    }
  }
  for (; x0 < w; ++x0) upsample_pixel(fine, x0, y, coarse, coarse_light, own, terms, out);
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace ssgi
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ssgi {
namespace detail {

HWY_EXPORT(UpsampleRowSimd);
HWY_EXPORT(DepthGradientRow);
HWY_EXPORT(DownsampleRowSimd);
HWY_EXPORT(JointBilateralRowSimd);

void depth_gradient_row_scalar(const float* z, int w, int h, int y, float* gx, float* gy) {
  for (int x = 0; x < w; ++x) depth_gradient_pixel(z, w, h, x, y, gx, gy);
}

void depth_gradient_row(const float* z, int w, int h, int y, float* gx, float* gy) {
  if (simd_forced_scalar()) {
    depth_gradient_row_scalar(z, w, h, y, gx, gy);
    return;
  }
  HWY_DYNAMIC_DISPATCH(DepthGradientRow)(z, w, h, y, gx, gy);
}

void joint_bilateral_row_scalar(const GuidePlanes& g, const float* const light[3], int y,
                                int radius, const float* taps, const RangeTerms& terms,
                                float* const out[3]) {
  for (int x = 0; x < g.width; ++x) joint_bilateral_pixel(g, light, x, y, radius, taps, terms, out);
}

void joint_bilateral_row(const GuidePlanes& g, const float* const light[3], int y, int radius,
                         const float* taps, const RangeTerms& terms, float* const out[3]) {
  if (simd_forced_scalar() || terms.integer_normal_power < 0) {
    joint_bilateral_row_scalar(g, light, y, radius, taps, terms, out);
    return;
  }
  HWY_DYNAMIC_DISPATCH(JointBilateralRowSimd)(g, light, y, radius, taps, terms, out);
}

void downsample_row_scalar(const GuidePlanes& fine, const float* const fine_light[3], int y,
                           int coarse_width, const RangeTerms& terms, const GuideRow& out,
                           float* const light_out[3]) {
  for (int x = 0; x < coarse_width; ++x)
    downsample_pixel(fine, fine_light, x, y, terms, out, light_out);
}

void downsample_row(const GuidePlanes& fine, const float* const fine_light[3], int y,
                    int coarse_width, const RangeTerms& terms, const GuideRow& out,
                    float* const light_out[3]) {
  if (simd_forced_scalar() || terms.integer_normal_power < 0) {
    downsample_row_scalar(fine, fine_light, y, coarse_width, terms, out, light_out);
    return;
  }
  HWY_DYNAMIC_DISPATCH(DownsampleRowSimd)(fine, fine_light, y, coarse_width, terms, out, light_out);
}

void upsample_row_scalar(const GuidePlanes& fine, int y, const GuidePlanes& coarse,
                         const float* const coarse_light[3], const float* const own[3],
                         const RangeTerms& terms, float* const out[3]) {
  for (int x = 0; x < fine.width; ++x)
    upsample_pixel(fine, x, y, coarse, coarse_light, own, terms, out);
}

void upsample_row(const GuidePlanes& fine, int y, const GuidePlanes& coarse,
                  const float* const coarse_light[3], const float* const own[3],
                  const RangeTerms& terms, float* const out[3]) {
  if (simd_forced_scalar() || terms.integer_normal_power < 0) {
    upsample_row_scalar(fine, y, coarse, coarse_light, own, terms, out);
    return;
  }
  HWY_DYNAMIC_DISPATCH(UpsampleRowSimd)(fine, y, coarse, coarse_light, own, terms, out);
}

}  // namespace detail
}  // namespace ssgi
#endif
