// The Embree reference against analytic answers and against a slow walk through the surface
// model, and the march converging to it as rays and steps grow (testdata/README.md describes
// each fixture).
#include "reference/reference.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "compare/compare.h"
#include "fixture_frame.h"
#include "frame_stages.h"
#include "gi/composite.h"
#include "gi/directions.h"
#include "gi/gather.h"
#include "gi/misses.h"
#include "gi/surface_model.h"
#include "io/frame_reader.h"
#include "ssgi/pipeline.h"

namespace ssgi {
namespace {

using Frame = test_fixtures::FixtureFrame;

Frame load(const std::string& pattern, const GiSettings& settings) {
  return test_fixtures::load_fixture(pattern, settings);
}

Image indirect(const Frame& f, const GiSettings& settings) {
  return Pipeline(f.seq, settings).indirect_light(f.g);
}

// One undenoised bounce under a constant environment, traced by the reference.
GiSettings reference_settings(int spp, std::array<float, 3> env) {
  GiSettings s;
  s.tracer = Tracer::kReference;
  s.rays = spp;
  s.bounces = 1;
  s.miss = MissMode::kEnvironment;
  s.env_color = env;
  s.denoise = DenoiseMode::kNone;
  return s;
}

// relRMSE of `a` against the reference `b` over surface pixels: RMSE / mean(b).
double relative_rmse(const Image& a, const Image& b, const GBuffer& g) {
  CompareOptions options;
  options.compute_ssim = false;
  const CompareResult r =
      compare_images(a, b, {{"indirect", {0, 1, 2}, true}}, options,
                     background_from_depth(g.depth.plane(0), g.depth.plane_size()));
  return *r.overall.metric(Metric::kRelRmse);
}

// Inside a closed box whose every surface reflects 0.5, with misses returning 0.5 too, every
// ray brings 0.5 whatever it hits: one bounce is 0.5 (the 1% bound).
TEST(Reference, FurnaceOneBounceIsL) {
  const GiSettings s = reference_settings(64, {0.5f, 0.5f, 0.5f});
  const Frame f = load("furnace/furnace.0001.exr", s);
  const Image result = indirect(f, s);
  for (float v : result.data()) ASSERT_NEAR(v, 0.5f, 0.005f);
}

// A lone plane cannot see itself, so every ray misses: exactly 0 under a black environment,
// and C under a constant C (to the rounding of a mean of 64 floats).
TEST(Reference, LonePlaneSeesOnlyTheEnvironment) {
  GiSettings s = reference_settings(64, {0, 0, 0});
  const Frame f = load("plane/plane.0001.exr", s);
  const Image black = indirect(f, s);
  for (float v : black.data()) ASSERT_EQ(v, 0.0f);

  s.env_color = {0.2f, 0.4f, 0.8f};
  const Image lit = indirect(f, s);
  for (int y = 0; y < f.g.height(); ++y) {
    for (int x = 0; x < f.g.width(); ++x) {
      if (!f.g.is_surface(x, y)) continue;
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(lit.at(c, x, y), s.env_color[c], 1e-5f);
    }
  }
}

// The reference has no screen edge to extend a surface beyond: --miss extend gives exactly what
// --miss env gives.
TEST(Reference, ExtendMissesSeeTheEnvironment) {
  GiSettings s = reference_settings(16, {0.1f, 0.2f, 0.3f});
  const Frame f = load("sample/sample.0001.exr", s);
  const Image env = indirect(f, s);
  s.miss = MissMode::kExtend;
  EXPECT_EQ(indirect(f, s).data(), env.data());
}

// The slow twin of the reference: the surface model taken literally. Walks the ray from `o`
// along `d`, cast from pixel (x, y), over its screen segment (clipped as the march clips it) in
// steps of 1/1000 pixel and returns the pixel DepthMesh::surface_at names at the first point
// inside a slab and outside the ray's own pixel, or -1.
int dense_walk(const GBuffer& g, const detail::DepthMesh& mesh, const Imath::V3f& o,
               const Imath::V3f& d, int x, int y) {
  float t_end = 1e6f * o.z;
  if (d.z < 0) t_end = std::min(t_end, (o.z - 1e-3f * o.z) / -d.z);
  const Imath::V3f e{o.x + t_end * d.x, o.y + t_end * d.y, o.z + t_end * d.z};
  const Camera& cam = g.camera;
  const double sx0 = cam.cx + cam.fx * o.x / o.z, sy0 = cam.cy - cam.fy * o.y / o.z;
  const double dx = cam.cx + cam.fx * e.x / e.z - sx0, dy = cam.cy - cam.fy * e.y / e.z - sy0;
  // Clip f in [0, 1] to the data window.
  double lo = 0, hi = 1;
  for (const auto& [p, q] : {std::pair{-dx, sx0}, std::pair{dx, g.width() - sx0},
                             std::pair{-dy, sy0}, std::pair{dy, g.height() - sy0}}) {
    if (p == 0) {
      if (q < 0) return -1;
    } else if (p < 0) {
      lo = std::max(lo, q / p);
    } else {
      hi = std::min(hi, q / p);
    }
  }
  if (!(hi > lo)) return -1;
  const double h0 = 1.0 / o.z, h1 = 1.0 / e.z;
  const int steps =
      static_cast<int>(std::ceil(std::max(std::fabs(dx), std::fabs(dy)) * (hi - lo) * 1000));
  for (int i = 0; i < steps; ++i) {
    const double f = lo + (hi - lo) * (i + 0.5) / steps;
    const float sx = static_cast<float>(sx0 + dx * f), sy = static_cast<float>(sy0 + dy * f);
    if (std::floor(sx) == x && std::floor(sy) == y) continue;
    detail::MeshPoint surface;
    if (!mesh.surface_at(sx, sy, &surface)) continue;
    const double z = 1.0 / (h0 + (h1 - h0) * f);
    if (z >= surface.z && z <= surface.back_z) return surface.pixel;
  }
  return -1;
}

// Every 7th pixel's 4 rays on the sample room, against the dense walk. They may differ only
// where a ray passes within a walk step of a triangle edge, a vertex's region or a slab face:
// 1 ray in 3416 does.
TEST(Reference, AgreesWithADenseWalkThroughTheModel) {
  const GiSettings s = reference_settings(4, {0, 0, 0});
  const Frame f = load("sample/sample.0001.exr", s);
  const GBuffer& g = f.g;
  const detail::Environment env;
  const detail::RayHits hits = detail::trace_reference(g, s, detail::MissModel(g, s.miss, env));
  const detail::SurfaceModel model{static_cast<float>(s.thickness)};
  const detail::DepthMesh mesh(g.depth, detail::feature_thickness(g, model));
  int rays = 0, differ = 0;
  for (int p = 0; p < g.width() * g.height(); p += 7) {
    const int x = p % g.width(), y = p / g.width();
    if (!g.is_surface(x, y)) continue;
    // The rays of march.cpp's trace_pixel (the sample's data window is its display window).
    const float z = g.depth.at(0, x, y);
    const Imath::V3d c = g.camera.unproject(x + 0.5, y + 0.5, z);
    const Imath::V3f n{g.normal.at(0, x, y), g.normal.at(1, x, y), g.normal.at(2, x, y)};
    const float off = static_cast<float>(s.start_offset) * z;
    const Imath::V3f o{static_cast<float>(c.x) + n.x * off, static_cast<float>(c.y) + n.y * off,
                       static_cast<float>(c.z) + n.z * off};
    const detail::PixelNoise noise = detail::pixel_noise(x, y, g.frame, s.seed);
    for (int k = 0; k < s.rays; ++k) {
      float u1, u2, jitter;
      detail::ray_sample(noise, k, &u1, &u2, &jitter);
      const int walk = dense_walk(g, mesh, o, detail::cosine_hemisphere(n, u1, u2), x, y);
      ++rays;
      const int hit = hits.hit[static_cast<std::size_t>(p) * s.rays + k];
      differ += (hit >= 0 ? detail::hit_pixel(hit) : hit) != walk ? 1 : 0;
    }
  }
  std::printf("%d of %d rays differ from the dense walk\n", differ, rays);
  EXPECT_GT(rays, 2500);
  EXPECT_LE(differ, rays / 1000);
}

// A mesh with bounds (DepthMesh::bound_quads, as the views' meshes have) skips what a ray
// cannot meet and marches to the same hits: the sampled march (segments longer than the step
// budget) to the same for every ray, the exact walk, restarted tile by tile, for all but the
// rays that pass within rounding of a cell's edge. The rays of every 3rd pixel of the sample
// room, with budgets that make most segments sampled (8 steps) or all of them exact.
TEST(Reference, BoundedMeshMarchesToTheSameHits) {
  const GiSettings s = reference_settings(4, {0, 0, 0});
  const Frame f = load("sample/sample.0001.exr", s);
  const GBuffer& g = f.g;
  const detail::SurfaceModel model{static_cast<float>(s.thickness)};
  const Image thickness = detail::feature_thickness(g, model);
  const detail::DepthMesh plain(g.depth, thickness);
  detail::DepthMesh bounded(g.depth, thickness);
  bounded.bound_quads();
  ASSERT_TRUE(bounded.bounded());
  ASSERT_FALSE(plain.bounded());
  // The bounds themselves: a point nearer than every surface is clear of each quad and tile;
  // one at the depth of a quad's corner is not, nor of its tile.
  float nearest = std::numeric_limits<float>::infinity();
  for (std::size_t q = 0; q < g.depth.plane_size(); ++q)
    nearest = std::min(nearest, g.depth.plane(0)[q]);
  int quads = 0;
  for (int j = 0; j + 1 < g.height(); ++j)
    for (int i = 0; i + 1 < g.width(); ++i) {
      if (!bounded.has_triangle(i, j, true) && !bounded.has_triangle(i, j, false)) continue;
      const float near = 2.0f / nearest, corner = 1.0f / g.depth.at(0, i, j);
      const int ti = i / detail::DepthMesh::kTile, tj = j / detail::DepthMesh::kTile;
      ASSERT_TRUE(bounded.clear_of(i, j, near, near)) << i << " " << j;
      ASSERT_TRUE(bounded.tile_clear_of(ti, tj, near, near)) << i << " " << j;
      ASSERT_FALSE(bounded.clear_of(i, j, corner, corner)) << i << " " << j;
      ASSERT_FALSE(bounded.tile_clear_of(ti, tj, corner, corner)) << i << " " << j;
      ASSERT_FALSE(plain.clear_of(i, j, near, near));
      ++quads;
    }
  EXPECT_GT(quads, 4000);
  const Camera& cam = g.camera;
  for (const int steps : {8, 4096}) {
    int rays = 0, hits = 0, differ = 0;
    for (int p = 0; p < g.width() * g.height(); p += 3) {
      const int x = p % g.width(), y = p / g.width();
      if (!g.is_surface(x, y)) continue;
      const detail::PixelRays pixel_rays(g, s, x, y);
      const Imath::V3f& o = pixel_rays.origin();
      for (int k = 0; k < 8; ++k) {
        float jitter;
        const Imath::V3f d = pixel_rays.direction(k, &jitter);
        // The segment as the march builds it (march.cpp, march_ray).
        float t_end = 1e6f * o.z;
        if (d.z < 0) t_end = std::min(t_end, (o.z - 1e-3f * o.z) / -d.z);
        const Imath::V3f e = o + t_end * d;
        const float sx0 = static_cast<float>(cam.cx + cam.fx * o.x / o.z);
        const float sy0 = static_cast<float>(cam.cy - cam.fy * o.y / o.z);
        detail::ScreenSegment seg{sx0,
                                  sy0,
                                  static_cast<float>(cam.cx + cam.fx * e.x / e.z) - sx0,
                                  static_cast<float>(cam.cy - cam.fy * e.y / e.z) - sy0,
                                  1.0f / o.z,
                                  1.0f / e.z,
                                  0.0f,
                                  1.0f};
        if (!std::isfinite(seg.dx) || !std::isfinite(seg.dy) ||
            !detail::clip_to_window(&seg, static_cast<float>(g.width()),
                                    static_cast<float>(g.height())))
          continue;
        const int a = detail::march_segment(plain, seg, steps, jitter, x, y);
        const int b = detail::march_segment(bounded, seg, steps, jitter, x, y);
        ++rays;
        hits += a >= 0;
        differ += a != b;
      }
    }
    std::printf("%d steps: %d rays, %d hits, %d differ\n", steps, rays, hits, differ);
    EXPECT_GT(rays, 10000);
    EXPECT_GT(hits, rays / 4);
    if (steps == 8)
      EXPECT_EQ(differ, 0);
    else
      EXPECT_LE(differ, rays / 10000);
  }
}

// The ray ends are the same for 1 and 2 threads, and run to run.
TEST(Reference, SameHitsForAnyThreadCount) {
  const GiSettings s = reference_settings(16, {0.1f, 0.2f, 0.3f});
  const Frame f = load("sample/sample.0001.exr", s);
  const detail::Environment env(s.env_color);
  const detail::MissModel misses(f.g, s.miss, env);
  detail::RayHits one, two, again;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = detail::trace_reference(f.g, s, misses);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = detail::trace_reference(f.g, s, misses);
    again = detail::trace_reference(f.g, s, misses);
  }
  EXPECT_EQ(one.hit, two.hit);
  EXPECT_EQ(two.hit, again.hit);
  EXPECT_EQ(one.env_sum.data(), two.env_sum.data());
}

// The bounded hits give the light of the whole frame's hits held at once (what the reference
// kept before, 4 bytes per ray of the frame), bit for bit, whether they keep every row, some or
// none (then each bounce traces again), for 1 and 2 threads.
TEST(Reference, BoundedHitsGiveTheLightOfAllHitsHeld) {
  GiSettings s = reference_settings(16, {0.1f, 0.2f, 0.3f});
  s.bounces = 3;
  s.miss = MissMode::kFrame;
  const Frame f = load("sample/sample.0001.exr", s);
  const detail::Environment env(s.env_color);
  const detail::TraceGrid grid =
      detail::make_trace_grid(f.g, false, 1, static_cast<float>(s.thickness));
  const detail::MissModel misses(f.g, s.miss, env);
  const Image held = detail::gather_bounces(
      grid, detail::weighted_from_rays(grid, detail::trace_reference(f.g, s, misses)), s.bounces,
      misses);
  double sum = 0;
  for (float v : held.data()) sum += v;
  ASSERT_GT(sum, 0);
  const std::size_t row = detail::ReferenceHits::row_bytes(f.g.width(), s.rays);
  for (const std::size_t budget : {std::size_t{0}, row * 5 + 1, row * f.g.height()}) {
    for (const int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      const detail::ReferenceHits hits(f.g, s, misses, budget);
      const Image bounded = detail::gather_bounces(grid, hits, s.bounces, misses);
      EXPECT_EQ(bounded.data(), held.data()) << "budget " << budget << ", " << threads;
    }
  }
  // And the pipeline's reference with a budget of no rows is the one with the default.
  const Image by_default = indirect(f, s);
  const Image no_rows_kept = detail::FrameStages(f.seq, s, PipelineMemory{0}).indirect_light(f.g);
  EXPECT_EQ(by_default.data(), no_rows_kept.data());
}

struct MarchSetting {
  int rays, max_steps;
};

// relRMSE of the march at each setting against the reference at 1024 spp, on the sample room
// with nothing between tracing and the result: no denoiser, one bounce, black misses.
std::vector<double> march_errors(const std::vector<MarchSetting>& settings) {
  const GiSettings ref = reference_settings(1024, {0, 0, 0});
  const Frame f = load("sample/sample.0001.exr", ref);
  const Image truth = indirect(f, ref);
  std::vector<double> errors;
  for (const MarchSetting& setting : settings) {
    GiSettings march = ref;
    march.tracer = Tracer::kScreenSpace;
    march.rays = setting.rays;
    march.max_steps = setting.max_steps;
    errors.push_back(relative_rmse(indirect(f, march), truth, f.g));
    std::printf("rays %4d, max steps %4d: relRMSE %.4f\n", setting.rays, setting.max_steps,
                errors.back());
  }
  return errors;
}

// The convergence test: as rays and steps grow the march's error against the reference
// (1024 rays per pixel) falls at every step and ends below 2% of the reference's mean. Ray k of
// the march is ray k of the reference, so at 1024 rays the noise cancels and what remains is
// the march's disagreement with the surface model. With a step budget that covers the ray the
// march walks the mesh exactly and agrees with Embree to float rounding (measured 0.0000, every
// ray of this 96x64 frame is shorter than 1024 px); the earlier rows are mostly noise.
TEST(Reference, MarchConvergesToTheReference) {
  const std::vector<double> errors =
      march_errors({{4, 8}, {16, 32}, {64, 128}, {256, 1024}, {1024, 1024}});
  for (std::size_t i = 1; i < errors.size(); ++i) EXPECT_LT(errors[i], errors[i - 1]) << i;
  EXPECT_LT(errors.back(), 0.02);
}

// The slice tracer on the same surface model: as slices (32 sectors each) and samples per side
// grow, its error against the reference falls at every step (at trace scale 1, undenoised, one
// bounce, black misses). Its directions are not the reference's rays, so what remains at the
// end is the reference's own noise at 1024 rays plus the slices' sampling of the mesh (measured
// 0.845, 0.246, 0.102, 0.068).
TEST(Reference, SliceTracerConvergesToTheReference) {
  const GiSettings ref = reference_settings(1024, {0, 0, 0});
  const Frame f = load("sample/sample.0001.exr", ref);
  const Image truth = indirect(f, ref);
  double mean = 0;
  for (float v : truth.data()) mean += v;
  ASSERT_GT(mean, 0);  // the reference itself finds light: a tracer that misses would fail below
  std::vector<double> errors;
  for (const auto& [slices, steps] :
       std::vector<std::pair<int, int>>{{1, 8}, {4, 32}, {16, 64}, {48, 192}}) {
    GiSettings s = ref;
    s.tracer = Tracer::kSlices;
    s.trace_scale = 1;
    s.slices = slices;
    s.max_steps = steps;
    errors.push_back(relative_rmse(indirect(f, s), truth, f.g));
    std::printf("slices %3d, samples %4d: relRMSE %.4f\n", slices, steps, errors.back());
  }
  for (std::size_t i = 1; i < errors.size(); ++i) EXPECT_LT(errors[i], errors[i - 1]) << i;
  EXPECT_LT(errors.back(), 0.08);
}

}  // namespace
}  // namespace ssgi
