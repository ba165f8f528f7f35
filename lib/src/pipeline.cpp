// The plan and the per-frame pipeline: directions -> march -> misses -> bounces -> denoise,
// and the composite after the temporal stage.
#include "ssgi/pipeline.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "composite.h"
#include "denoise.h"
#include "environment.h"
#include "march.h"
#include "ssgi/error.h"

namespace ssgi {
namespace {

std::string color_string(const std::array<float, 3>& c) {
  std::ostringstream s;
  s << c[0] << "," << c[1] << "," << c[2];
  return s.str();
}

void validate(const GiSettings& s) {
  if (s.rays < 1 || s.rays > 4096) throw_usage("--rays must be between 1 and 4096");
  if (s.max_steps < 1 || s.max_steps > 1 << 20)
    throw_usage("--max-steps must be between 1 and 1048576");
  if (!(s.max_distance >= 0) || !std::isfinite(s.max_distance))
    throw_usage("--max-distance must be >= 0 (0: unlimited)");
  if (!(s.thickness > 0) || !std::isfinite(s.thickness))
    throw_usage("--thickness must be > 0");
  if (!(s.start_offset >= 0) || s.start_offset > 1)
    throw_usage("the start offset must be between 0 and 1");
  if (s.bounces < 1 || s.bounces > 64) throw_usage("--bounces must be between 1 and 64");
  for (float c : s.env_color)
    if (!(c >= 0) || !std::isfinite(c)) throw_usage("--env-color must be finite and >= 0");
  if (s.env_up != 'y' && s.env_up != 'z') throw_usage("--env-up must be y or z");
}

}  // namespace

Plan make_plan(const SequenceInfo& seq, const GiSettings& s) {
  validate(s);
  const Layout& layout = seq.layout;
  Plan plan;
  auto need = [&](Role role, const std::string& why) {
    plan.roles |= role_bit(role);
    plan.reasons.push_back(std::string("read ") + role_name(role) + ": " + why);
  };
  need(Role::kDepth, "the surfaces rays start from and hit");
  need(Role::kNormal, "the hemisphere each pixel gathers over");
  if (!layout.has(Role::kDirect))
    throw_input(seq.pattern.path_for(seq.frames.front()),
                "has no direct-light channels (give --channel direct=NAME)");
  need(Role::kDirect, "the light surfaces reflect");
  if (!layout.has(Role::kAlbedo))
    throw_input(seq.pattern.path_for(seq.frames.front()),
                "has no albedo channels (give --channel albedo=NAME)");
  need(Role::kAlbedo, layout.preset.direct_includes_albedo ? "gi = albedo x indirect"
                                                           : "direct light x albedo, and gi");
  plan.gather_emission = s.gather_emission < 0 ? layout.preset.gather_emission
                                               : s.gather_emission > 0;
  if (layout.has(Role::kEmission)) {
    need(Role::kEmission, plan.gather_emission ? "added to the composite and gathered by rays"
                                               : "added to the composite (not gathered: the "
                                                 "renderer samples emitters as lights)");
  } else {
    plan.gather_emission = false;
  }
  if (layout.has(Role::kBeauty)) need(Role::kBeauty, "background pixels and alpha of the composite");
  plan.env_map = !s.env_map.empty();
  const std::string env =
      plan.env_map ? "environment map " + s.env_map + " (up axis " + s.env_up + ")"
                   : "constant colour " + color_string(s.env_color);
  plan.reasons.push_back(s.miss == MissMode::kFrame
                             ? "misses: estimated from the frame (mean reflected light of its "
                               "surfaces, and " + env + " for its background fraction)"
                             : "misses: " + env);
  plan.cache_hits = s.bounces > 1;
  plan.reasons.push_back(
      "march: " + std::to_string(s.rays) + " rays per pixel, up to " +
      std::to_string(s.max_steps) + " steps, " + std::to_string(s.bounces) + " bounce" +
      (s.bounces > 1 ? "s (hits kept and re-gathered for each further bounce)" : ""));
  plan.denoise = s.denoise == DenoiseMode::kPyramid;
  plan.reasons.push_back(plan.denoise ? "denoise: bilateral pyramid" : "denoise: none");
  plan.temporal = TemporalMode::kNone;
  plan.reasons.push_back("temporal: none (not available yet)");
  plan.reasons.push_back("composite: direct + emission + albedo x indirect");
  return plan;
}

struct Pipeline::Impl {
  GiSettings settings;
  Plan plan;
  detail::Environment env;
};

Pipeline::Pipeline(const SequenceInfo& seq, const GiSettings& settings)
    : impl_(std::make_unique<Impl>()) {
  impl_->settings = settings;
  impl_->plan = make_plan(seq, settings);
  impl_->env = settings.env_map.empty()
                   ? detail::Environment(settings.env_color)
                   : detail::Environment::from_file(settings.env_map, settings.env_up);
}

Pipeline::~Pipeline() = default;

const Plan& Pipeline::plan() const { return impl_->plan; }
const GiSettings& Pipeline::settings() const { return impl_->settings; }

namespace {

// How enclosed the camera is, from the frame's border: the fraction of border pixels whose
// surface runs alongside the view on its side (a ceiling along the top edge faces down, a
// floor along the bottom faces up, side walls face inwards). A room seen from inside scores
// near 1; a set seen from outside (a backdrop along the top, sky) scores low.
double enclosure(const GBuffer& g) {
  const int w = g.width(), h = g.height();
  const int ring = std::max(1, std::min(w, h) / 50);
  std::size_t border = 0, inward = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int dl = x, dr = w - 1 - x, dt = y, db = h - 1 - y;
      const int nearest = std::min(std::min(dl, dr), std::min(dt, db));
      if (nearest >= ring) continue;
      ++border;
      if (!g.is_surface(x, y)) continue;
      const float nx = g.normal.at(0, x, y), ny = g.normal.at(1, x, y);
      const bool faces_in = (nearest == dt && ny < -0.5f) || (nearest == db && ny > 0.5f) ||
                            (nearest == dl && nx > 0.5f) || (nearest == dr && nx < -0.5f);
      inward += faces_in ? 1 : 0;
    }
  }
  return border ? static_cast<double>(inward) / border : 0.0;
}

// The weight of the frame estimate for misses (MissMode::kFrame, kAuto): the fraction of the
// frame that shows surfaces, and for kAuto how enclosed the camera is, ramped so that a score
// near the threshold does not switch abruptly between frames.
double closure_weight(const GBuffer& g, MissMode mode) {
  if (mode == MissMode::kEnvironment || mode == MissMode::kExtend) return 0.0;
  const int w = g.width(), h = g.height();
  std::size_t surfaces = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) surfaces += g.is_surface(x, y) ? 1 : 0;
  const double surface_fraction = static_cast<double>(surfaces) / (static_cast<double>(w) * h);
  if (mode == MissMode::kFrame) return surface_fraction;
  const double t = std::clamp((enclosure(g) - 0.4) / 0.2, 0.0, 1.0);
  return surface_fraction * t * t * (3 - 2 * t);
}

// What misses bring when gathering `radiance`: the environment weighted by 1 - closure, plus
// closure x the mean light the frame's surfaces reflect.
detail::MissLight miss_light(const GBuffer& g, const Image& radiance, double closure) {
  detail::MissLight miss;
  miss.env_weight = static_cast<float>(1.0 - closure);
  if (closure <= 0) return miss;
  const int w = g.width(), h = g.height();
  // Sums in double, in a fixed order: the same bits for any thread count.
  double sum[3] = {0, 0, 0};
  std::size_t surfaces = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      ++surfaces;
      for (int c = 0; c < 3; ++c) sum[c] += radiance.at(c, x, y);
    }
  }
  for (int c = 0; c < 3; ++c)
    miss.frame_radiance[c] = surfaces ? static_cast<float>(closure * sum[c] / surfaces) : 0.0f;
  return miss;
}

}  // namespace

Image Pipeline::indirect_light(const GBuffer& g) const {
  const GiSettings& s = impl_->settings;
  const Plan& plan = impl_->plan;
  const Image reflected = detail::reflected_radiance(g, plan.gather_emission);
  const double closure = closure_weight(g, s.miss);
  Image indirect;
  if (!plan.cache_hits) {
    indirect = detail::march_and_gather(g, s, impl_->env, reflected,
                                        miss_light(g, reflected, closure));
  } else {
    // Each further bounce re-gathers over the same rays: the light a surface reflects after
    // bounce b is its direct light plus albedo x indirect of bounce b.
    const detail::RayHits hits = detail::march_screen_space(g, s, impl_->env);
    indirect = detail::gather_indirect(g, hits, reflected, miss_light(g, reflected, closure));
    for (int b = 1; b < s.bounces; ++b) {
      Image radiance = reflected;
      for (int c = 0; c < 3; ++c) {
        float* r = radiance.plane(c);
        const float* a = g.albedo.plane(c);
        const float* ind = indirect.plane(c);
        // Albedo above 1 would add energy at every bounce.
        for (std::size_t p = 0; p < radiance.plane_size(); ++p)
          r[p] += std::clamp(a[p], 0.0f, 1.0f) * ind[p];
      }
      indirect = detail::gather_indirect(g, hits, radiance, miss_light(g, radiance, closure));
    }
  }
  if (plan.denoise)
    indirect = detail::denoise_pyramid(indirect, g.depth, g.normal, s.denoise_settings);
  return indirect;
}

FrameResult Pipeline::composite(const GBuffer& g, Image indirect) const {
  return detail::composite_frame(g, std::move(indirect));
}

}  // namespace ssgi
