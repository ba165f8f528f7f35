// Google Benchmark of one frame's GI stages at the resolution of the frame given in
// SSGI_BENCH_FRAME (default: the 1080p room that tests/bench/make_1080p.sh writes to
// /tmp/ssgi1080/room.0001.exr): read, trace grid, slice tracing, bounces, denoise, composite,
// and the whole indirect light. Not a test: build/bin/bench_stages [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "composite.h"
#include "denoise.h"
#include "denoise_kernels.h"
#include "environment.h"
#include "gather.h"
#include "misses.h"
#include "slice_kernel.h"
#include "slices.h"
#include "ssgi/io.h"
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
  ssgi::Image reflected;
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
    l.reflected = ssgi::detail::reflected_radiance(l.g, false);
    l.scale = ssgi::make_plan(l.seq, l.s).trace_scale;
    for (int k = l.scale; k > 1; k /= 2) ++l.level;
    l.grid = ssgi::detail::make_trace_grid(l.g, l.reflected, l.scale, 0.1f);
    l.hits = ssgi::detail::trace_slices(l.g, l.grid, l.s, ssgi::detail::Environment());
    l.traced = ssgi::detail::gather_bounces(l.grid, l.hits, l.s.bounces, 0.5);
    return l;
  }();
  return l;
}

void BM_Read(benchmark::State& state) {
  Loaded& l = frame();
  const ssgi::RoleMask roles = ssgi::make_plan(l.seq, l.s).roles;
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::read_gbuffer(l.seq, l.seq.frames.front(), roles, l.in));
}
void BM_ReflectedAndClosure(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state) {
    benchmark::DoNotOptimize(ssgi::detail::reflected_radiance(l.g, false));
    benchmark::DoNotOptimize(ssgi::detail::closure_weight(l.g, ssgi::MissMode::kAuto));
  }
}
void BM_TraceGrid(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::make_trace_grid(l.g, l.reflected, l.scale, 0.1f));
}
void BM_TraceSlices(benchmark::State& state) {
  Loaded& l = frame();
  const ssgi::detail::Environment env;
  for (auto _ : state) benchmark::DoNotOptimize(ssgi::detail::trace_slices(l.g, l.grid, l.s, env));
  state.counters["hits/sample"] = static_cast<double>(l.hits.entries()) / l.grid.origin.size();
}
void BM_Bounces(benchmark::State& state) {
  Loaded& l = frame();
  for (auto _ : state)
    benchmark::DoNotOptimize(ssgi::detail::gather_bounces(l.grid, l.hits, l.s.bounces, 0.5));
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

// The kernels alone, on a million values in cache-sized batches: argument 0 the scalar twin,
// 1 the SIMD version (the same bits; the ratio is the kernel's own speed-up).
void BM_RangeWeightsKernel(benchmark::State& state) {
  constexpr std::size_t kBatch = 4096;
  ssgi::detail::RangeBatch batch;
  batch.resize(kBatch);
  for (std::size_t k = 0; k < kBatch; ++k) {
    const float a = 0.001f * static_cast<float>(k % 977);
    const ssgi::detail::Surface p{2.0f + a, 0.6f, 0.0f, -0.8f, 0.01f, -0.02f};
    const ssgi::detail::Surface q{2.0f + 1.01f * a, 0.6f - a, 0.1f, -0.79f, 0, 0};
    batch.set(k, p, q, 1.0f, -1.0f);
  }
  const ssgi::detail::RangeTerms terms = ssgi::detail::make_range_terms({});
  std::vector<float> out(kBatch);
  for (auto _ : state) {
    for (int r = 0; r < 256; ++r) {
      if (state.range(0))
        ssgi::detail::range_weights(batch, terms, out.data());
      else
        ssgi::detail::range_weights_scalar(batch, terms, out.data());
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.counters["weights/s"] =
      benchmark::Counter(256.0 * kBatch, benchmark::Counter::kIsIterationInvariantRate);
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
  const ssgi::detail::SliceFrame f{0.1f, 0.2f, 3.0f,  -0.03f, -0.07f, -0.997f, 0.99f, 0.0f, -0.03f,
                                   1.1f, 0.9f, 0.43f, -1.12f, 2.02f,  -0.4f,   25.0f, 0.3f};
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

BENCHMARK(BM_RangeWeightsKernel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MarchSideKernel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Read)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReflectedAndClosure)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TraceGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TraceSlices)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Bounces)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Denoise)->Unit(benchmark::kMillisecond);
void BM_Composite(benchmark::State& state) {
  Loaded& l = frame();
  const ssgi::Pipeline pipeline(l.seq, l.s);
  const ssgi::Image indirect = pipeline.indirect_light(l.g);
  for (auto _ : state) benchmark::DoNotOptimize(pipeline.composite(l.g, indirect));
}

BENCHMARK(BM_IndirectLight)->Unit(benchmark::kMillisecond);
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
