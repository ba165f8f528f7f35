// The slice tracer's kernel, compiled once per SIMD target (Highway's foreach_target).
#include "slice_kernel.h"

#include "range_weights.h"  // simd_forced_scalar

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "slice_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace ssgi {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

template <class D, class V>
V Atan2(D d, V y, V x) {
  const V ax = hn::Abs(x), ay = hn::Abs(y);
  const V hi = hn::Max(ax, ay), lo = hn::Min(ax, ay);
  const V a = hn::Div(lo, hi), s = hn::Mul(a, a);
  V r = hn::Add(hn::Mul(hn::Set(d, -0.0040540580f), s), hn::Set(d, 0.0218612288f));
  r = hn::Sub(hn::Mul(r, s), hn::Set(d, 0.0559098861f));
  r = hn::Add(hn::Mul(r, s), hn::Set(d, 0.0964200441f));
  r = hn::Sub(hn::Mul(r, s), hn::Set(d, 0.1390853351f));
  r = hn::Add(hn::Mul(r, s), hn::Set(d, 0.1994653599f));
  r = hn::Sub(hn::Mul(r, s), hn::Set(d, 0.3332985605f));
  r = hn::Add(hn::Mul(hn::Mul(r, s), a), a);
  r = hn::IfThenElse(hn::Gt(ay, ax), hn::Sub(hn::Set(d, 0.5f * kSlicePi), r), r);
  r = hn::IfThenElse(hn::Lt(x, hn::Zero(d)), hn::Sub(hn::Set(d, kSlicePi), r), r);
  r = hn::IfThenElse(hn::Lt(y, hn::Zero(d)), hn::Neg(r), r);
  return hn::IfThenZeroElse(hn::Eq(hi, hn::Zero(d)), r);
}

template <class D, class V>
V SectorCoordinate(D d, const SliceFrame& f, V wx, V wy, V wz) {
  const V c = hn::Add(hn::Add(hn::Mul(wx, hn::Set(d, f.vx)), hn::Mul(wy, hn::Set(d, f.vy))),
                      hn::Mul(wz, hn::Set(d, f.vz)));
  const V s = hn::Add(hn::Add(hn::Mul(wx, hn::Set(d, f.tx)), hn::Mul(wy, hn::Set(d, f.ty))),
                      hn::Mul(wz, hn::Set(d, f.tz)));
  const V inv = hn::Div(hn::Set(d, 1.0f), hn::Sqrt(hn::Add(hn::Mul(c, c), hn::Mul(s, s))));
  V theta = Atan2(d, s, c), sn = hn::Mul(s, inv), cs = hn::Mul(c, inv);
  const V cg = hn::Set(d, f.cg), sg = hn::Set(d, f.sg);
  const auto below = hn::Lt(theta, hn::Set(d, f.lo_theta));
  theta = hn::IfThenElse(below, hn::Set(d, f.lo_theta), theta);
  sn = hn::IfThenElse(below, hn::Neg(cg), sn);
  cs = hn::IfThenElse(below, sg, cs);
  const auto above = hn::Gt(theta, hn::Set(d, f.hi_theta));
  theta = hn::IfThenElse(above, hn::Set(d, f.hi_theta), theta);
  sn = hn::IfThenElse(above, cg, sn);
  cs = hn::IfThenElse(above, hn::Neg(sg), cs);
  const V g = hn::Mul(hn::Set(d, 0.5f), hn::Add(hn::Mul(hn::Mul(cg, sn), sn),
                                                hn::Mul(sg, hn::Sub(theta, hn::Mul(sn, cs)))));
  const V m = hn::IfThenElse(hn::Lt(sn, hn::Zero(d)), hn::Neg(g), g);
  return hn::Sub(hn::Mul(hn::Sub(m, hn::Set(d, f.h_lo)), hn::Set(d, f.to_sector)),
                 hn::Set(d, f.u_rot));
}

void SlabSectorCoordinates(const SliceFrame& f, const float* x, const float* y, const float* z,
                           std::size_t n, float* front, float* back) {
  const hn::ScalableTag<float> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto ox = hn::Set(d, f.ox), oy = hn::Set(d, f.oy), oz = hn::Set(d, f.oz);
  const auto scale = hn::Set(d, f.back_scale);
  std::size_t k = 0;
  for (; k + lanes <= n; k += lanes) {
    const auto px = hn::LoadU(d, x + k), py = hn::LoadU(d, y + k), pz = hn::LoadU(d, z + k);
    hn::StoreU(SectorCoordinate(d, f, hn::Sub(px, ox), hn::Sub(py, oy), hn::Sub(pz, oz)), d,
               front + k);
    hn::StoreU(SectorCoordinate(d, f, hn::Sub(hn::Mul(scale, px), ox),
                                hn::Sub(hn::Mul(scale, py), oy), hn::Sub(hn::Mul(scale, pz), oz)),
               d, back + k);
  }
  slab_sector_coordinates_scalar(f, x + k, y + k, z + k, n - k, front + k, back + k);
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace ssgi
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ssgi {
namespace detail {

HWY_EXPORT(SlabSectorCoordinates);

void slab_sector_coordinates_scalar(const SliceFrame& f, const float* x, const float* y,
                                    const float* z, std::size_t n, float* front, float* back) {
  for (std::size_t k = 0; k < n; ++k) {
    front[k] = sector_coordinate(f, x[k] - f.ox, y[k] - f.oy, z[k] - f.oz);
    back[k] = sector_coordinate(f, f.back_scale * x[k] - f.ox, f.back_scale * y[k] - f.oy,
                                f.back_scale * z[k] - f.oz);
  }
}

void slab_sector_coordinates(const SliceFrame& f, const float* x, const float* y, const float* z,
                             std::size_t n, float* front, float* back) {
  if (simd_forced_scalar()) {
    slab_sector_coordinates_scalar(f, x, y, z, n, front, back);
    return;
  }
  HWY_DYNAMIC_DISPATCH(SlabSectorCoordinates)(f, x, y, z, n, front, back);
}

}  // namespace detail
}  // namespace ssgi
#endif
