// The range-weight kernel, compiled once per SIMD target (Highway's foreach_target).
#include "range_weights.h"

#include <cstdlib>
#include <string>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "range_weights.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace ssgi {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// range_weight (range_weights.h) on lanes, operation for operation: the constants once per
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

  V operator()(V pz, V pnx, V pny, V pnz, V pgx, V pgy, V qz, V qnx, V qny, V qnz, V dx,
               V dy) const {
    const V dz = hn::Sub(hn::Sub(hn::Sub(qz, pz), hn::Mul(pgx, dx)), hn::Mul(pgy, dy));
    const V s = hn::Div(hn::Mul(dz, inv_sigma), pz);
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
    const V scale =
        hn::BitCast(d, hn::ShiftLeft<23>(hn::Add(hn::ConvertTo(di, whole), hn::Set(di, 127))));
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

void RangeWeightsSimd(const RangeBatch& b, const RangeTerms& terms, float* out) {
  const hn::ScalableTag<float> d;
  const RangeWeightV<decltype(d)> weight(terms);
  const std::size_t n = b.size(), lanes = hn::Lanes(d);
  std::size_t k = 0;
  for (; k + lanes <= n; k += lanes) {
    auto load = [&](const std::vector<float>& v) { return hn::LoadU(d, &v[k]); };
    hn::StoreU(weight(load(b.pz), load(b.pnx), load(b.pny), load(b.pnz), load(b.pgx), load(b.pgy),
                      load(b.qz), load(b.qnx), load(b.qny), load(b.qnz), load(b.dx), load(b.dy)),
               d, out + k);
  }
  for (; k < n; ++k) out[k] = range_weight_at(b, k, terms);
}

void UpsampleRowSimd(const GuidePlanes& fine, int y, const GuidePlanes& coarse,
                     const float* const coarse_light[3], const float* const own[3],
                     const RangeTerms& terms, float* const out[3]) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  using VF = hn::Vec<decltype(d)>;
  using VI = hn::Vec<decltype(di)>;
  const RangeWeightV<decltype(d)> weight(terms);
  const int w = fine.width, lanes = static_cast<int>(hn::Lanes(d));
  const std::size_t row = static_cast<std::size_t>(y) * w;
  // Along y the row's two coarse rows and their weights (upsampling_taps in the scalar twin).
  const int first_y = y % 2 == 0 ? y / 2 - 1 : y / 2;
  const float second_wy = y % 2 == 0 ? 0.75f : 0.25f;
  const int cy[2] = {std::clamp(first_y, 0, coarse.height - 1),
                     std::clamp(first_y + 1, 0, coarse.height - 1)};
  const float wy[2] = {1.0f - second_wy, second_wy};
  const VI last_x = hn::Set(di, coarse.width - 1), one_i = hn::Set(di, 1);
  const VF quarter = hn::Set(d, 0.25f), three_quarters = hn::Set(d, 0.75f), half = hn::Set(d, 0.5f);
  int x0 = 0;
  for (; x0 + lanes <= w; x0 += lanes) {
    const std::size_t i = row + static_cast<std::size_t>(x0);
    const VF pz = hn::LoadU(d, fine.z + i), pnx = hn::LoadU(d, fine.nx + i),
             pny = hn::LoadU(d, fine.ny + i), pnz = hn::LoadU(d, fine.nz + i),
             pgx = hn::LoadU(d, fine.gx + i), pgy = hn::LoadU(d, fine.gy + i);
    const VI x = hn::Add(hn::Iota(di, 0), hn::Set(di, x0));
    const VI first_x = hn::ShiftRight<1>(hn::Sub(x, one_i));  // floor((x - 1) / 2)
    const auto odd = hn::RebindMask(d, hn::Ne(hn::And(x, one_i), hn::Zero(di)));
    const VF wx[2] = {hn::IfThenElse(odd, three_quarters, quarter),
                      hn::IfThenElse(odd, quarter, three_quarters)};
    const VI cx[2] = {hn::Min(hn::Max(first_x, hn::Zero(di)), last_x),
                      hn::Min(hn::Max(hn::Add(first_x, one_i), hn::Zero(di)), last_x)};
    VF sum = hn::Set(d, kOwnValueWeight);
    VF light[3], own_light[3], lo[3], hi[3];
    for (int c = 0; c < 3; ++c) {
      own_light[c] = lo[c] = hi[c] = hn::LoadU(d, own[c] + x0);
      light[c] = hn::Mul(sum, own_light[c]);
    }
    for (int ky = 0; ky < 2; ++ky) {
      const VI coarse_row = hn::Set(di, cy[ky] * coarse.width);
      const VF dy = hn::Set(d, static_cast<float>(2 * cy[ky] - y) + 0.5f);
      for (int kx = 0; kx < 2; ++kx) {
        const VI j = hn::Add(coarse_row, cx[kx]);
        const VF dx = hn::Add(hn::ConvertTo(d, hn::Sub(hn::Add(cx[kx], cx[kx]), x)), half);
        const VF range = weight(pz, pnx, pny, pnz, pgx, pgy, hn::GatherIndex(d, coarse.z, j),
                                hn::GatherIndex(d, coarse.nx, j), hn::GatherIndex(d, coarse.ny, j),
                                hn::GatherIndex(d, coarse.nz, j), dx, dy);
        const VF wq = hn::Mul(hn::Mul(wx[kx], hn::Set(d, wy[ky])), range);
        sum = hn::Add(sum, wq);
        const auto counts = hn::Gt(wq, hn::Zero(d));
        for (int c = 0; c < 3; ++c) {
          const VF v = hn::GatherIndex(d, coarse_light[c], j);
          light[c] = hn::Add(light[c], hn::Mul(wq, v));
          const VF counted = hn::IfThenElse(counts, v, own_light[c]);
          lo[c] = hn::Min(lo[c], counted), hi[c] = hn::Max(hi[c], counted);
        }
      }
    }
    const auto surface = hn::Lt(pz, hn::Set(d, kInf));
    for (int c = 0; c < 3; ++c)
      hn::StoreU(
          hn::IfThenElseZero(surface, hn::Min(hn::Max(hn::Div(light[c], sum), lo[c]), hi[c])), d,
          out[c] + x0);
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

HWY_EXPORT(RangeWeightsSimd);
HWY_EXPORT(UpsampleRowSimd);

bool simd_forced_scalar() {
  static const bool forced = [] {
    const char* v = std::getenv("SSGI_SIMD");
    return v != nullptr && std::string(v) == "scalar";
  }();
  return forced;
}

void range_weights_scalar(const RangeBatch& b, const RangeTerms& terms, float* out) {
  for (std::size_t k = 0; k < b.size(); ++k) out[k] = range_weight_at(b, k, terms);
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

void range_weights(const RangeBatch& b, const RangeTerms& terms, float* out) {
  if (simd_forced_scalar() || terms.integer_normal_power < 0) {
    range_weights_scalar(b, terms, out);
    return;
  }
  HWY_DYNAMIC_DISPATCH(RangeWeightsSimd)(b, terms, out);
}

}  // namespace detail
}  // namespace ssgi
#endif
