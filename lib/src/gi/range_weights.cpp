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

// range_weight (range_weights.h) on Lanes(d) pairs at a time, operation for operation.
void RangeWeightsSimd(const RangeBatch& b, const RangeTerms& terms, float* out) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  const std::size_t n = b.size(), lanes = hn::Lanes(d);
  const auto zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  const auto inv_sigma = hn::Set(d, terms.inv_sigma_depth);
  const auto max_exponent = hn::Set(d, kMaxExponent);
  const auto log2e = hn::Set(d, 1.44269504f);
  const auto c1 = hn::Set(d, 0.6931472f), c2 = hn::Set(d, 0.2402265f), c3 = hn::Set(d, 0.05550357f),
             c4 = hn::Set(d, 0.009618129f), c5 = hn::Set(d, 0.001333355f),
             c6 = hn::Set(d, 0.0001540353f);
  const auto bias = hn::Set(di, 127);
  std::size_t k = 0;
  for (; k + lanes <= n; k += lanes) {
    const auto pz = hn::LoadU(d, &b.pz[k]), qz = hn::LoadU(d, &b.qz[k]);
    const auto dz =
        hn::Sub(hn::Sub(hn::Sub(qz, pz), hn::Mul(hn::LoadU(d, &b.pgx[k]), hn::LoadU(d, &b.dx[k]))),
                hn::Mul(hn::LoadU(d, &b.pgy[k]), hn::LoadU(d, &b.dy[k])));
    const auto s = hn::Div(hn::Mul(dz, inv_sigma), pz);
    const auto exponent = hn::Mul(hn::Mul(half, s), s);
    const auto valid = hn::Lt(exponent, max_exponent);
    // exp_negative
    const auto t = hn::Mul(hn::Neg(exponent), log2e);
    const auto whole = hn::Floor(t);
    const auto f = hn::Sub(t, whole);
    auto poly = hn::Add(c5, hn::Mul(f, c6));
    poly = hn::Add(c4, hn::Mul(f, poly));
    poly = hn::Add(c3, hn::Mul(f, poly));
    poly = hn::Add(c2, hn::Mul(f, poly));
    poly = hn::Add(c1, hn::Mul(f, poly));
    poly = hn::Add(one, hn::Mul(f, poly));
    const auto scale = hn::BitCast(d, hn::ShiftLeft<23>(hn::Add(hn::ConvertTo(di, whole), bias)));
    auto w = hn::Mul(poly, scale);
    // The normal term.
    const auto pnx = hn::LoadU(d, &b.pnx[k]), pny = hn::LoadU(d, &b.pny[k]),
               pnz = hn::LoadU(d, &b.pnz[k]);
    const auto qnx = hn::LoadU(d, &b.qnx[k]), qny = hn::LoadU(d, &b.qny[k]),
               qnz = hn::LoadU(d, &b.qnz[k]);
    const auto cos_angle =
        hn::Add(hn::Add(hn::Mul(pnx, qnx), hn::Mul(pny, qny)), hn::Mul(pnz, qnz));
    auto x = hn::Min(cos_angle, one);
    auto term = one;
    for (int p = terms.integer_normal_power; p > 0; p >>= 1, x = hn::Mul(x, x))
      if (p & 1) term = hn::Mul(term, x);
    const auto facing = hn::Gt(cos_angle, zero);
    const auto p_normal = hn::Or(hn::Or(hn::Ne(pnx, zero), hn::Ne(pny, zero)), hn::Ne(pnz, zero));
    const auto q_normal = hn::Or(hn::Or(hn::Ne(qnx, zero), hn::Ne(qny, zero)), hn::Ne(qnz, zero));
    w = hn::IfThenElse(facing, hn::Mul(w, term),
                       hn::IfThenZeroElse(hn::And(p_normal, q_normal), w));
    hn::StoreU(hn::IfThenElseZero(valid, w), d, out + k);
  }
  for (; k < n; ++k) out[k] = range_weight_at(b, k, terms);
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace ssgi
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ssgi {
namespace detail {

HWY_EXPORT(RangeWeightsSimd);

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
