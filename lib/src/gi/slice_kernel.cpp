// The slice tracer's kernel, compiled once per SIMD target (Highway's foreach_target).
#include "gi/slice_kernel.h"

#include "gi/denoise_kernels.h"  // simd_forced_scalar

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "gi/slice_kernel.cpp"
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
HWY_INLINE V SectorCoordinate(D d, const SliceFrame& f, V wx, V wy, V wz) {
  const V c = hn::Add(hn::Add(hn::Mul(wx, hn::Set(d, f.vx)), hn::Mul(wy, hn::Set(d, f.vy))),
                      hn::Mul(wz, hn::Set(d, f.vz)));
  const V s = hn::Add(hn::Add(hn::Mul(wx, hn::Set(d, f.tx)), hn::Mul(wy, hn::Set(d, f.ty))),
                      hn::Mul(wz, hn::Set(d, f.tz)));
  const V inv = hn::Div(hn::Set(d, 1.0f), hn::Add(hn::Mul(c, c), hn::Mul(s, s)));
  V theta = Atan2(d, s, c), sin2 = hn::Mul(hn::Mul(s, s), inv),
    sin_cos = hn::Mul(hn::Mul(s, c), inv);
  auto below_view = hn::Lt(s, hn::Zero(d));
  const V clamped_sin2 = hn::Set(d, f.cg * f.cg), clamped_sin_cos = hn::Set(d, -(f.cg * f.sg));
  const auto below = hn::Lt(theta, hn::Set(d, f.lo_theta));
  theta = hn::IfThenElse(below, hn::Set(d, f.lo_theta), theta);
  sin2 = hn::IfThenElse(below, clamped_sin2, sin2);
  sin_cos = hn::IfThenElse(below, clamped_sin_cos, sin_cos);
  below_view = f.cg > 0 ? hn::Or(below, below_view) : hn::AndNot(below, below_view);
  const auto above = hn::Gt(theta, hn::Set(d, f.hi_theta));
  theta = hn::IfThenElse(above, hn::Set(d, f.hi_theta), theta);
  sin2 = hn::IfThenElse(above, clamped_sin2, sin2);
  sin_cos = hn::IfThenElse(above, clamped_sin_cos, sin_cos);
  below_view = f.cg < 0 ? hn::Or(above, below_view) : hn::AndNot(above, below_view);
  const V g = hn::Mul(
      hn::Set(d, 0.5f),
      hn::Add(hn::Mul(hn::Set(d, f.cg), sin2), hn::Mul(hn::Set(d, f.sg), hn::Sub(theta, sin_cos))));
  const V m = hn::IfThenElse(below_view, hn::Neg(g), g);
  return hn::Sub(hn::Mul(hn::Sub(m, hn::Set(d, f.h_lo)), hn::Set(d, f.to_sector)),
                 hn::Set(d, f.u_rot));
}

// The sectors ceil(lo) .. floor(hi) as bits: sector_bits on lanes.
template <class D, class V>
hn::Vec<hn::RebindToUnsigned<D>> SectorBits(D d, V lo, V hi) {
  const hn::RebindToSigned<D> di;
  const hn::RebindToUnsigned<D> du;
  const V k0f = hn::Min(hn::Max(hn::Ceil(lo), hn::Zero(d)), hn::Set(d, 32.0f));
  const V k1f = hn::Min(hn::Max(hn::Floor(hi), hn::Set(d, -1.0f)), hn::Set(d, 31.0f));
  const auto nonempty = hn::And(hn::Gt(hi, lo), hn::Le(k0f, k1f));
  // Shift counts kept in 0..31 on every lane (the empty ones are cleared below).
  const auto k0 = hn::And(hn::BitCast(du, hn::ConvertTo(di, hn::Min(k0f, hn::Set(d, 31.0f)))),
                          hn::Set(du, 31u));
  const auto k1 =
      hn::And(hn::BitCast(du, hn::ConvertTo(di, hn::Max(k1f, hn::Zero(d)))), hn::Set(du, 31u));
  const auto all = hn::Set(du, ~0u);
  const auto bits = hn::And(all >> hn::Sub(hn::Set(du, 31u), k1), all << k0);
  return hn::IfThenElseZero(hn::RebindMask(du, nonempty), bits);
}

// std::min and std::max on lanes, NaN handling included: min(a, b) = b < a ? b : a.
template <class V>
V MinLike(V a, V b) {
  return hn::IfThenElse(hn::Lt(b, a), b, a);
}
template <class V>
V MaxLike(V a, V b) {
  return hn::IfThenElse(hn::Lt(a, b), b, a);
}

int MarchSide(const MeshView& mesh, const SliceFrame& f, const SideMarch& m, SideSamples* out) {
  const hn::ScalableTag<float> d;
  const hn::RebindToSigned<decltype(d)> di;
  using VF = hn::Vec<decltype(d)>;
  using VI = hn::Vec<decltype(di)>;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int padded = (m.steps + lanes - 1) / lanes * lanes;
  const float* inverse_depths = reinterpret_cast<const float*>(mesh.texels);
  const std::int32_t* words = reinterpret_cast<const std::int32_t*>(mesh.texels);
  const VF one = hn::Set(d, 1.0f), zero = hn::Zero(d);
  const VI one_i = hn::Set(di, 1), width = hn::Set(di, mesh.width);
  const VF width_f = hn::Set(d, static_cast<float>(mesh.width));
  const VF height_f = hn::Set(d, static_cast<float>(mesh.height));
  const VF inv_steps = hn::Set(d, 1.0f / static_cast<float>(m.steps));
  const VF steps_f = hn::Set(d, static_cast<float>(m.steps));
  const VF t_span = hn::Set(d, m.t_max - 1.0f);
  const VF ox = hn::Set(d, f.ox), oy = hn::Set(d, f.oy), oz = hn::Set(d, f.oz);
  const VF thickness_unit = hn::Set(d, 1.0f / kThicknessSteps);
  const VF model_thickness = hn::Set(d, m.thickness);
  const VI steps_i = hn::Set(di, kThicknessSteps);
  const VF normal_unit = hn::Set(d, 1.0f / 127.0f);
  out->pixel[0] = -1;
  out->z[0] = out->x[0] = out->y[0] = out->nx[0] = out->ny[0] = out->nz[0] = 0.0f;
  out->front_u[0] = out->back_u[0] = out->thickness[0] = 0.0f;

  // The samples: where each meets the mesh, and its slab's sector coordinates (and their
  // extremes, bound_backs).
  const VF inf = hn::Set(d, std::numeric_limits<float>::infinity());
  VF above = inf, below = hn::Neg(inf);
  for (int j = 0; j < padded; j += lanes) {
    const VF step = hn::Add(hn::Iota(d, 0.0f), hn::Set(d, static_cast<float>(j)));
    const VF frac = hn::Mul(hn::Add(step, hn::Set(d, m.u_step)), inv_steps);
    const VF dist = hn::Add(one, hn::Mul(hn::Mul(t_span, frac), frac));
    const VF px = hn::Add(hn::Set(d, m.qx), hn::Mul(hn::Set(d, m.sx), dist));
    const VF py = hn::Add(hn::Set(d, m.qy), hn::Mul(hn::Set(d, m.sy), dist));
    const VF u = hn::Sub(px, hn::Set(d, 0.5f)), v = hn::Sub(py, hn::Set(d, 0.5f));
    const VF fi = hn::Floor(u), fj = hn::Floor(v);
    const auto inside = hn::And(
        hn::And(hn::And(hn::Ge(fi, zero), hn::Ge(fj, zero)),
                hn::And(hn::Lt(hn::Add(fi, one), width_f), hn::Lt(hn::Add(fj, one), height_f))),
        hn::Lt(step, steps_f));
    const auto inside_i = hn::RebindMask(di, inside);
    const VF fu = hn::Sub(u, fi), fv = hn::Sub(v, fj);
    const auto upper = hn::Ge(fu, fv);
    const auto upper_i = hn::RebindMask(di, upper);
    // Corner indices; 0 (any texel) off the mesh, so that every gather stays inside.
    const VI a = hn::IfThenElseZero(
        inside_i, hn::Add(hn::Mul(hn::ConvertTo(di, fj), width), hn::ConvertTo(di, fi)));
    const VI b =
        hn::IfThenElseZero(inside_i, hn::IfThenElse(upper_i, hn::Add(a, one_i), hn::Add(a, width)));
    const VI c = hn::IfThenElseZero(inside_i, hn::Add(hn::Add(a, width), one_i));
    const VI flags = hn::ShiftRight<24>(hn::GatherIndex(di, words, hn::Add(hn::Add(a, a), one_i)));
    const VI wanted =
        hn::IfThenElse(upper_i, hn::Set(di, kUpperTriangle), hn::Set(di, kLowerTriangle));
    const auto valid_i =
        hn::And(inside_i, hn::Ne(hn::And(hn::And(flags, hn::Set(di, 0xff)), wanted), hn::Zero(di)));
    const VF wa = hn::IfThenElse(upper, hn::Sub(one, fu), hn::Sub(one, fv));
    const VF wb = hn::IfThenElse(upper, hn::Sub(fu, fv), hn::Sub(fv, fu));
    const VF wc = hn::IfThenElse(upper, fv, fu);
    const VF ia = hn::GatherIndex(d, inverse_depths, hn::Add(a, a));
    const VF ib = hn::GatherIndex(d, inverse_depths, hn::Add(b, b));
    const VF ic = hn::GatherIndex(d, inverse_depths, hn::Add(c, c));
    const VF z = hn::Div(one, hn::Add(hn::Add(hn::Mul(wa, ia), hn::Mul(wb, ib)), hn::Mul(wc, ic)));
    const auto pick_a = hn::RebindMask(di, hn::And(hn::Ge(wa, wb), hn::Ge(wa, wc)));
    const auto pick_b = hn::RebindMask(di, hn::Ge(wb, wc));
    const VI pixel = hn::IfThenElse(pick_a, a, hn::IfThenElse(pick_b, b, c));
    const VI word = hn::GatherIndex(di, words, hn::Add(hn::Add(pixel, pixel), one_i));
    const VF nx =
        hn::Mul(normal_unit, hn::ConvertTo(d, hn::ShiftRight<24>(hn::ShiftLeft<24>(word))));
    const VF ny =
        hn::Mul(normal_unit, hn::ConvertTo(d, hn::ShiftRight<24>(hn::ShiftLeft<16>(word))));
    const VF nz =
        hn::Mul(normal_unit, hn::ConvertTo(d, hn::ShiftRight<24>(hn::ShiftLeft<8>(word))));
    const VF x = hn::Mul(z, hn::Mul(hn::Sub(px, hn::Set(d, m.cx)), hn::Set(d, m.inv_fx)));
    const VF y = hn::Mul(z, hn::Mul(hn::Sub(hn::Set(d, m.cy), py), hn::Set(d, m.inv_fy)));
    const std::size_t at = static_cast<std::size_t>(j) + 1;
    const VF wx = hn::Sub(x, ox), wy = hn::Sub(y, oy), wz = hn::Sub(z, oz);
    // The vertex's slab (its texel's thickness code, thickness_of_code's terms).
    const VI code = hn::And(hn::ShiftRight<24 + kThicknessShift>(word), hn::Set(di, 63));
    const VF thick =
        hn::Mul(model_thickness, hn::Mul(hn::ConvertTo(d, hn::Sub(steps_i, code)), thickness_unit));
    const VF back_scale = hn::Add(one, thick);
    // Seen from behind (surface_model.h): the origin is behind the vertex's tangent plane,
    // n . o < n . p - tolerance x z with p = r / h the vertex's point (r its ray at z = 1, h its
    // 1/z, z = 1/h), i.e. h n . o < n . r - tolerance.
    const VF half = hn::Set(d, 0.5f);
    const VF vx = hn::IfThenElse(
        hn::RebindMask(d, pick_a), fi,
        hn::IfThenElse(hn::And(hn::RebindMask(d, pick_b), hn::Not(upper)), fi, hn::Add(fi, one)));
    const VF vy = hn::IfThenElse(
        hn::RebindMask(d, pick_a), fj,
        hn::IfThenElse(hn::And(hn::RebindMask(d, pick_b), upper), fj, hn::Add(fj, one)));
    const VF hv = hn::IfThenElse(hn::RebindMask(d, pick_a), ia,
                                 hn::IfThenElse(hn::RebindMask(d, pick_b), ib, ic));
    const VF rx = hn::Mul(hn::Sub(hn::Add(vx, half), hn::Set(d, m.cx)), hn::Set(d, m.inv_fx));
    const VF ry = hn::Mul(hn::Sub(hn::Set(d, m.cy), hn::Add(vy, half)), hn::Set(d, m.inv_fy));
    const VF n_dot_o = hn::Add(hn::Add(hn::Mul(nx, ox), hn::Mul(ny, oy)), hn::Mul(nz, oz));
    const VF n_dot_r = hn::Add(hn::Add(hn::Mul(nx, rx), hn::Mul(ny, ry)), nz);
    const auto behind = hn::RebindMask(
        di, hn::Lt(hn::Mul(hv, n_dot_o), hn::Sub(n_dot_r, hn::Set(d, kBehindTolerance))));
    const VI marked = hn::IfThenElse(behind, hn::Or(pixel, hn::Set(di, kSeenFromBehind)), pixel);
    hn::StoreU(hn::IfThenElse(valid_i, marked, hn::Set(di, -1)), di, out->pixel.data() + at);
    hn::StoreU(x, d, out->x.data() + at);
    hn::StoreU(y, d, out->y.data() + at);
    hn::StoreU(z, d, out->z.data() + at);
    hn::StoreU(nx, d, out->nx.data() + at);
    hn::StoreU(ny, d, out->ny.data() + at);
    hn::StoreU(nz, d, out->nz.data() + at);
    hn::StoreU(thick, d, out->thickness.data() + at);
    const VF front_u = SectorCoordinate(d, f, wx, wy, wz);
    const VF back_u =
        SectorCoordinate(d, f, hn::Sub(hn::Mul(back_scale, x), ox),
                         hn::Sub(hn::Mul(back_scale, y), oy), hn::Sub(hn::Mul(back_scale, z), oz));
    hn::StoreU(front_u, d, out->front_u.data() + at);
    hn::StoreU(back_u, d, out->back_u.data() + at);
    const auto valid = hn::RebindMask(d, valid_i);
    above = hn::Min(above, hn::IfThenElse(hn::And(valid, hn::Gt(back_u, front_u)), back_u, inf));
    below = hn::Max(below,
                    hn::IfThenElse(hn::And(valid, hn::Lt(back_u, front_u)), back_u, hn::Neg(inf)));
    if (m.max_distance2 > 0)
      hn::StoreU(hn::Add(hn::Add(hn::Mul(wx, wx), hn::Mul(wy, wy)), hn::Mul(wz, wz)), d,
                 out->distance2.data() + at);
  }

  // The sectors each sample shadows, bridged to the one before on one continuous surface.
  for (int j = 0; j < padded; j += lanes) {
    const std::size_t at = static_cast<std::size_t>(j) + 1, before = at - 1;
    const VI none = hn::Set(di, -1);
    const auto valid = hn::Gt(hn::LoadU(di, out->pixel.data() + at), none);
    const auto valid_before = hn::Gt(hn::LoadU(di, out->pixel.data() + before), none);
    const VF fa = hn::LoadU(d, out->front_u.data() + at),
             fb = hn::LoadU(d, out->back_u.data() + at);
    const VF pa = hn::LoadU(d, out->front_u.data() + before);
    const VF pb = hn::LoadU(d, out->back_u.data() + before);
    const VF lo = MinLike(fa, fb), hi = MaxLike(fa, fb);
    const VF nx = hn::LoadU(d, out->nx.data() + at), pnx = hn::LoadU(d, out->nx.data() + before);
    const VF ny = hn::LoadU(d, out->ny.data() + at), pny = hn::LoadU(d, out->ny.data() + before);
    const VF nz = hn::LoadU(d, out->nz.data() + at), pnz = hn::LoadU(d, out->nz.data() + before);
    const VF z = hn::LoadU(d, out->z.data() + at), pz = hn::LoadU(d, out->z.data() + before);
    const VF t = hn::LoadU(d, out->thickness.data() + at);
    const VF pt = hn::LoadU(d, out->thickness.data() + before);
    const VF dx = hn::Sub(hn::LoadU(d, out->x.data() + at), hn::LoadU(d, out->x.data() + before));
    const VF dy = hn::Sub(hn::LoadU(d, out->y.data() + at), hn::LoadU(d, out->y.data() + before));
    const VF dz = hn::Sub(z, pz);
    const VF facing = hn::Add(hn::Add(hn::Mul(nx, pnx), hn::Mul(ny, pny)), hn::Mul(nz, pnz));
    const VF off_plane = hn::Add(hn::Add(hn::Mul(pnx, dx), hn::Mul(pny, dy)), hn::Mul(pnz, dz));
    const auto coplanar =
        hn::And(hn::Gt(facing, hn::Set(d, 0.9f)),
                hn::Le(hn::Abs(off_plane), hn::Mul(MinLike(pt, t), MinLike(pz, z))));
    const auto connected = hn::And(
        hn::And(hn::IsFinite(pz), hn::IsFinite(z)),
        hn::And(hn::Le(z, hn::Mul(pz, hn::Add(one, pt))), hn::Le(pz, hn::Mul(z, hn::Add(one, t)))));
    const auto bridge =
        hn::And(hn::RebindMask(d, hn::And(valid, valid_before)), hn::Or(coplanar, connected));
    const VF lo2 = hn::IfThenElse(bridge, MinLike(lo, MinLike(pa, pb)), lo);
    const VF hi2 = hn::IfThenElse(bridge, MaxLike(hi, MaxLike(pa, pb)), hi);
    const hn::RebindToUnsigned<decltype(d)> du;
    hn::StoreU(hn::IfThenElseZero(hn::RebindMask(du, valid), SectorBits(d, lo2, hi2)), du,
               out->bits.data() + j);
  }
  int end = m.steps;
  if (m.max_distance2 > 0)
    for (int j = 0; j < m.steps; ++j)
      if (out->pixel[j + 1] >= 0 && out->distance2[j + 1] > m.max_distance2) {
        end = j;
        break;
      }
  if (end == m.steps) {
    // Lane by lane: some targets' MinOfLanes and MaxOfLanes start from the largest finite
    // float, not from the infinities the scalar twin keeps where no slab counts.
    float lanes_above[HWY_MAX_BYTES / sizeof(float)], lanes_below[HWY_MAX_BYTES / sizeof(float)];
    hn::StoreU(above, d, lanes_above);
    hn::StoreU(below, d, lanes_below);
    out->beyond_above = std::numeric_limits<float>::infinity();
    out->beyond_below = -out->beyond_above;
    for (int k = 0; k < lanes; ++k) {
      out->beyond_above = std::min(out->beyond_above, lanes_above[k]);
      out->beyond_below = std::max(out->beyond_below, lanes_below[k]);
    }
  } else {
    bound_backs(out, end);
  }
  return end;
}

int CollectHits(const SideSamples& samples, int count, float sector_weight, std::uint32_t* mask,
                std::int32_t* pixel, float* weight) {
  return collect_hits_with(samples, count, sector_weight, mask, pixel, weight,
                           [](std::uint32_t v) { return hwy::PopCount(v); });
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace ssgi
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ssgi {
namespace detail {

HWY_EXPORT(MarchSide);
HWY_EXPORT(CollectHits);

void SideSamples::reserve(int steps) {
  // Whole vectors of up to 16 lanes, and the leading entry for "no step before the first".
  const std::size_t n = static_cast<std::size_t>(steps) + 33;
  if (pixel.size() >= n) return;
  for (auto* v : {&x, &y, &z, &nx, &ny, &nz, &thickness, &front_u, &back_u, &distance2})
    v->resize(n);
  pixel.resize(n);
  bits.resize(n);
}

int march_side_scalar(const MeshView& mesh, const SliceFrame& f, const SideMarch& m,
                      SideSamples* out) {
  out->reserve(m.steps);
  const float inv_steps = 1.0f / static_cast<float>(m.steps);
  const float width_f = static_cast<float>(mesh.width);
  const float height_f = static_cast<float>(mesh.height);
  auto min_like = [](float a, float b) { return b < a ? b : a; };
  auto max_like = [](float a, float b) { return a < b ? b : a; };
  int end = m.steps;
  bool before_valid = false;
  float before_x = 0, before_y = 0, before_z = 0, before_n[3] = {0, 0, 0}, before_lo = 0,
        before_hi = 0, before_thick = 0;
  for (int j = 0; j < m.steps; ++j) {
    out->bits[j] = 0;
    out->pixel[j + 1] = -1;
    const float frac = (static_cast<float>(j) + m.u_step) * inv_steps;
    const float dist = 1.0f + (m.t_max - 1.0f) * frac * frac;
    const float px = m.qx + m.sx * dist, py = m.qy + m.sy * dist;
    const float u = px - 0.5f, v = py - 0.5f;
    const float fi = std::floor(u), fj = std::floor(v);
    const bool inside = fi >= 0 && fj >= 0 && fi + 1.0f < width_f && fj + 1.0f < height_f;
    const bool valid_before = before_valid;
    before_valid = false;
    if (!inside) continue;
    const float fu = u - fi, fv = v - fj;
    const bool upper = fu >= fv;
    const int a = static_cast<int>(fj) * mesh.width + static_cast<int>(fi);
    if (!(mesh.texels[a].triangles & (upper ? kUpperTriangle : kLowerTriangle))) continue;
    const int b = upper ? a + 1 : a + mesh.width, c = a + mesh.width + 1;
    const float wa = upper ? 1.0f - fu : 1.0f - fv;
    const float wb = upper ? fu - fv : fv - fu;
    const float wc = upper ? fv : fu;
    const float ia = mesh.texels[a].inverse_depth, ib = mesh.texels[b].inverse_depth,
                ic = mesh.texels[c].inverse_depth;
    const float z = 1.0f / (wa * ia + wb * ib + wc * ic);
    const bool pick_a = wa >= wb && wa >= wc, pick_b = wb >= wc;
    const int pixel = pick_a ? a : pick_b ? b : c;
    const MeshTexel& t = mesh.texels[pixel];
    constexpr float k = 1.0f / 127.0f;
    const float n[3] = {k * static_cast<float>(t.nx), k * static_cast<float>(t.ny),
                        k * static_cast<float>(t.nz)};
    // Seen from behind: the origin behind the vertex's tangent plane (the SIMD kernel's terms).
    const float vx = pick_a || (pick_b && !upper) ? fi : fi + 1.0f;
    const float vy = pick_a || (pick_b && upper) ? fj : fj + 1.0f;
    const float hv = pick_a ? ia : pick_b ? ib : ic;
    const float rx = ((vx + 0.5f) - m.cx) * m.inv_fx, ry = (m.cy - (vy + 0.5f)) * m.inv_fy;
    const float n_dot_o = (n[0] * f.ox + n[1] * f.oy) + n[2] * f.oz;
    const float n_dot_r = (n[0] * rx + n[1] * ry) + n[2];
    const bool behind = hv * n_dot_o < n_dot_r - kBehindTolerance;
    const float x = z * ((px - m.cx) * m.inv_fx), y = z * ((m.cy - py) * m.inv_fy);
    const float wx = x - f.ox, wy = y - f.oy, wz = z - f.oz;
    if (m.max_distance2 > 0 && wx * wx + wy * wy + wz * wz > m.max_distance2) {
      end = j;
      break;
    }
    const float thick = thickness_of_code(t.triangles >> kThicknessShift, m.thickness);
    const float back_scale = 1.0f + thick;
    const float fa = sector_coordinate(f, wx, wy, wz);
    const float fb =
        sector_coordinate(f, back_scale * x - f.ox, back_scale * y - f.oy, back_scale * z - f.oz);
    float lo = min_like(fa, fb), hi = max_like(fa, fb);
    const float own_lo = lo, own_hi = hi;
    if (valid_before) {
      const float facing = n[0] * before_n[0] + n[1] * before_n[1] + n[2] * before_n[2];
      const float off_plane = before_n[0] * (x - before_x) + before_n[1] * (y - before_y) +
                              before_n[2] * (z - before_z);
      const bool coplanar = facing > 0.9f && std::fabs(off_plane) <= min_like(before_thick, thick) *
                                                                         min_like(before_z, z);
      const bool connected = std::isfinite(before_z) && std::isfinite(z) &&
                             z <= before_z * (1.0f + before_thick) && before_z <= z * back_scale;
      if (coplanar || connected) {
        lo = min_like(lo, before_lo);
        hi = max_like(hi, before_hi);
      }
    }
    out->bits[j] = sector_bits(lo, hi);
    out->pixel[j + 1] = mark_side(pixel, behind);
    out->front_u[j + 1] = fa;
    out->back_u[j + 1] = fb;
    before_valid = true;
    before_x = x, before_y = y, before_z = z, before_thick = thick;
    before_n[0] = n[0], before_n[1] = n[1], before_n[2] = n[2];
    before_lo = own_lo, before_hi = own_hi;
  }
  bound_backs(out, end);
  return end;
}

int collect_hits_scalar(const SideSamples& samples, int count, float sector_weight,
                        std::uint32_t* mask, std::int32_t* pixel, float* weight) {
  return collect_hits_with(samples, count, sector_weight, mask, pixel, weight, sector_count);
}

int collect_hits(const SideSamples& samples, int count, float sector_weight, std::uint32_t* mask,
                 std::int32_t* pixel, float* weight) {
  if (simd_forced_scalar())
    return collect_hits_scalar(samples, count, sector_weight, mask, pixel, weight);
  return HWY_DYNAMIC_DISPATCH(CollectHits)(samples, count, sector_weight, mask, pixel, weight);
}

int march_side(const MeshView& mesh, const SliceFrame& f, const SideMarch& m, SideSamples* out) {
  out->reserve(m.steps);
  if (simd_forced_scalar()) return march_side_scalar(mesh, f, m, out);
  return HWY_DYNAMIC_DISPATCH(MarchSide)(mesh, f, m, out);
}

}  // namespace detail
}  // namespace ssgi
#endif
