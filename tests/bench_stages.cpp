// Google Benchmark of one frame's GI stages at the resolution of the frame given in
// SSGI_BENCH_FRAME (default: the 1080p room that tests/bench/make_1080p.sh writes to
// /tmp/ssgi1080/room.0001.exr): read, trace grid, slice tracing, bounces, denoise, composite,
// and the whole indirect light; with SSGI_BENCH_VIEWS (the frame's views as --view takes them,
// space-separated), the views' own light (light_views) and the whole indirect light with them.
// Not a test: build/bin/bench_stages [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "frame_stages.h"
#include "gi/composite.h"
#include "gi/denoise.h"
#include "gi/denoise_kernels.h"
#include "gi/environment.h"
#include "gi/gather.h"
#include "gi/misses.h"
#include "gi/slice_kernel.h"
#include "gi/slices.h"
#include "io/frame_reader.h"
#include "io/views.h"
#include "plan.h"
#include "ssgi/pipeline.h"
#include "ssgi/threads.h"

namespace {

std::string frame_path() {
  const char* env = std::getenv("SSGI_BENCH_FRAME");
  return env ? env : "/tmp/ssgi1080/room.0001.exr";
}

struct Loaded {
  ssgi::InputOptions in;
  ssgi::SequenceInfo seq;
  ssgi::GBuffer g;
  ssgi::GiSettings s;
  ssgi::detail::Environment env;
  std::unique_ptr<ssgi::detail::MissModel> misses;
  ssgi::detail::TraceGrid grid;
  ssgi::detail::WeightedHits hits;
  ssgi::Image traced;
  int scale = 1, level = 0;  // the plan's trace scale and its pyramid level
};

Loaded& frame() {
  static Loaded l = [] {
    Loaded l;
    l.in.pattern = frame_path();
    l.seq = ssgi::open_sequence(l.in);
    l.g = ssgi::read_gbuffer(l.seq, l.seq.frames.front(), ssgi::make_plan(l.seq, l.s).roles, l.in);
    l.scale = ssgi::make_plan(l.seq, l.s).trace_scale;
    for (int k = l.scale; k > 1; k /= 2) ++l.level;
    l.grid = ssgi::detail::make_trace_grid(l.g, false, l.scale, 0.1f);
    l.misses = std::make_unique<ssgi::detail::MissModel>(l.g, l.s.miss, l.env);
    l.hits = ssgi::detail::trace_slices(l.g, l.grid, l.s, *l.misses);
    l.traced = ssgi::detail::gather_bounces(l.grid, l.hits, l.s.bounces, *l.misses);
    return l;
  }();
  return l;
}

// The frame again with its views (SSGI_BENCH_VIEWS), read as the run reads them.
struct LoadedViews {
  ssgi::SequenceInfo seq;
  std::vector<ssgi::GBuffer> views;
};

LoadedViews& views() {
  static LoadedViews v = [] {
    LoadedViews v;
    const char* env = std::getenv("SSGI_BENCH_VIEWS");
    if (!env) return v;
    ssgi::InputOptions in = frame().in;
    std::istringstream patterns(env);
    for (std::string p; patterns >> p;) in.views.push_back({p});
    if (in.views.empty()) return v;
    v.seq = ssgi::open_sequence(in);
    v.views = ssgi::detail::read_views(v.seq, frame().g.frame, in, nullptr);
    return v;
  }();
  return v;
}

void BM_Read(benchmark::State& state) {
  Loaded& l = frame();
  const ssgi::RoleMask roles = ssgi::make_plan(l.seq, l.s).roles;
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::read_gbuffer(l.seq, l.seq.frames.front(), roles, l.in));
}
void BM_MissModel(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::MissModel(l.g, ssgi::MissMode::kAuto, l.env));
}
void BM_TraceGrid(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::make_trace_grid(l.g, false, l.scale, 0.1f));
}
void BM_TraceSlices(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::trace_slices(l.g, l.grid, l.s, *l.misses));
  state.counters["hits/sample"] = static_cast<double>(l.hits.entries()) / l.grid.origin.size();
}
// The same, also recording the missed rays for the views and the other frames to continue.
void BM_TraceSlicesRecordingMisses(benchmark::State& state) {
  Loaded& l = frame();
  std::size_t rays = 0;
  for (auto _ : state) {
    ssgi::detail::MissedRays missed;
    benchmark::DoNotOptimize(ssgi::detail::trace_slices(l.g, l.grid, l.s, *l.misses, &missed));
    rays = missed.rays.size();
  }
  state.counters["missed rays"] = static_cast<double>(rays);
}
void BM_Bounces(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::gather_bounces(l.grid, l.hits, l.s.bounces, *l.misses));
}
void BM_Denoise(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::upsample_and_denoise(
        l.traced, l.level, l.g.depth, l.g.normal, l.s.denoise_settings, true));
}
void BM_IndirectLight(benchmark::State& state) {
  Loaded& l = frame();
  const ssgi::Pipeline pipeline(l.seq, l.s);
  for (auto _ : state) benchmark::DoNotOptimize(pipeline.indirect_light(l.g));
}
void BM_LightViews(benchmark::State& state) {
  const LoadedViews& v = views();
  if (v.views.empty()) return state.SkipWithError("no SSGI_BENCH_VIEWS");
  const ssgi::detail::FrameStages stages(v.seq, frame().s, {});
  for (auto _ : state) benchmark::DoNotOptimize(stages.light_views(v.views));
}
void BM_IndirectLightWithViews(benchmark::State& state) {
  const LoadedViews& v = views();
  if (v.views.empty()) return state.SkipWithError("no SSGI_BENCH_VIEWS");
  const ssgi::Pipeline pipeline(v.seq, frame().s);
  for (auto _ : state)
    benchmark::DoNotOptimize(pipeline.indirect_light(frame().g, nullptr, &v.views));
}

// The kernels alone, on a million values in cache-sized batches: argument 0 the scalar twin,
// 1 the SIMD version (the same bits; the ratio is the kernel's own speed-up).
// The joint bilateral filter's row kernel (5x5, the default at the pyramid's coarsest level)
// over a 480x270 level of a tilted plane with depth steps and background.
void BM_JointBilateralKernel(benchmark::State& state) {
  constexpr int kWidth = 480, kHeight = 270, kRadius = 2;
  const std::size_t n = static_cast<std::size_t>(kWidth) * kHeight;
  std::vector<float> z(n), nx(n, 0.0f), ny(n, 0.6f), nz(n, -0.8f), gx(n, 0.01f), gy(n, -0.02f);
  std::vector<float> light(3 * n), out(3 * static_cast<std::size_t>(kWidth));
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (std::size_t i = 0; i < n; ++i) {
    const float r = u(rng);
    z[i] = r < 0.03f ? ssgi::detail::kInf
                     : 2.0f + 0.001f * static_cast<float>(i % kWidth) + (r < 0.08f ? 0.5f : 0.0f);
    for (int c = 0; c < 3; ++c) light[c * n + i] = u(rng);
  }
  const ssgi::detail::GuidePlanes g{z.data(),  nx.data(), ny.data(), nz.data(),
                                    gx.data(), gy.data(), kWidth,    kHeight};
  const float* const planes[3] = {light.data(), light.data() + n, light.data() + 2 * n};
  float* const rows[3] = {out.data(), out.data() + kWidth, out.data() + 2 * kWidth};
  const float taps[kRadius + 1] = {1.0f, 0.8f, 0.41f};
  const ssgi::detail::RangeTerms terms = ssgi::detail::make_range_terms({});
  for (auto _ : state) {
    for (int y = 0; y < kHeight; ++y) {
      if (state.range(0))
        ssgi::detail::joint_bilateral_row(g, planes, y, kRadius, taps, terms, rows);
      else
        ssgi::detail::joint_bilateral_row_scalar(g, planes, y, kRadius, taps, terms, rows);
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.counters["pixels/s"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
}

// One side of a slice after another over a 480x270 mesh of a tilted plane with holes, in
// random directions: the tracer's whole per-sample work but the bookkeeping of hits.
void BM_MarchSideKernel(benchmark::State& state) {
  constexpr int kWidth = 480, kHeight = 270, kSides = 4096, kSteps = 28;
  std::vector<ssgi::detail::MeshTexel> texels(kWidth * kHeight);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int j = 0; j < kHeight; ++j)
    for (int i = 0; i < kWidth; ++i) {
      auto& t = texels[j * kWidth + i];
      t.inverse_depth = 1.0f / (4.0f + 0.01f * static_cast<float>(i) + (u(rng) < 0.05f ? 2 : 0));
      t.nx = 0, t.ny = 90, t.nz = -90;
      t.triangles = u(rng) < 0.02f ? 0 : 3;
    }
  const ssgi::detail::MeshView mesh{texels.data(), kWidth, kHeight};
  std::vector<ssgi::detail::SideMarch> sides(kSides);
  for (auto& m : sides) {
    const float angle = 6.2831853f * u(rng);
    m = {kWidth * u(rng),
         kHeight * u(rng),
         std::cos(angle),
         std::sin(angle),
         200.0f * u(rng) + 2,
         u(rng),
         kSteps,
         kWidth / 2,
         kHeight / 2,
         1.0f / kWidth,
         1.0f / kWidth,
         0,
         0.1f};
  }
  const ssgi::detail::SliceFrame f{0.1f,   0.2f, 3.0f,  -0.03f, -0.07f, -0.997f, 0.99f, 0.0f,
                                   -0.03f, 0.9f, 0.43f, -1.12f, 2.02f,  -0.4f,   25.0f, 0.3f};
  ssgi::detail::SideSamples out;
  for (auto _ : state) {
    for (const auto& m : sides) {
      if (state.range(0))
        ssgi::detail::march_side(mesh, f, m, &out);
      else
        ssgi::detail::march_side_scalar(mesh, f, m, &out);
      benchmark::DoNotOptimize(out.bits.data());
    }
  }
  state.counters["samples/s"] = benchmark::Counter(static_cast<double>(kSides) * kSteps,
                                                   benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_JointBilateralKernel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MarchSideKernel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Read)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MissModel)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TraceGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TraceSlices)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TraceSlicesRecordingMisses)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Bounces)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Denoise)->Unit(benchmark::kMillisecond);
void BM_Composite(benchmark::State& state) {
  Loaded& l = frame();
  const ssgi::Pipeline pipeline(l.seq, l.s);
  const ssgi::Image indirect = pipeline.indirect_light(l.g);
  for (auto _ : state) benchmark::DoNotOptimize(pipeline.composite(l.g, indirect));
}

BENCHMARK(BM_IndirectLight)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LightViews)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IndirectLightWithViews)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Composite)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  if (!std::filesystem::exists(frame_path())) {
    std::fprintf(stderr,
                 "bench_stages: no %s (make it with tests/bench/make_1080p.sh, or set "
                 "SSGI_BENCH_FRAME)\n",
                 frame_path().c_str());
    return 1;
  }
  // SSGI_BENCH_THREADS=1 for single-thread timings (steadier on a shared machine).
  const char* threads = std::getenv("SSGI_BENCH_THREADS");
  const ssgi::ThreadLimit limit(threads ? std::atoi(threads) : 0);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
