// Google Benchmark of the pipeline's stages on the Cycles sample data (../shared/data/room,
// 320x180): reading a frame, march + gather, bounces, denoise, and the whole frame.
// Not a test: build/bin/bench_pipeline [--benchmark_repetitions=5 ...]
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "io/frame_reader.h"
#include "plan.h"
#include "ssgi/pipeline.h"
#include "ssgi/threads.h"

namespace {

const std::string kRoom = std::string(SSGI_SHARED_DATA_DIR) + "/room/room.####.exr";

struct Loaded {
  ssgi::InputOptions in;
  ssgi::SequenceInfo seq;
  ssgi::GBuffer g;
};

const Loaded& room() {
  static const Loaded loaded = [] {
    Loaded l;
    l.in.pattern = kRoom;
    l.seq = ssgi::open_sequence(l.in);
    l.g = ssgi::read_gbuffer(l.seq, 1, ssgi::make_plan(l.seq, {}).roles, l.in);
    return l;
  }();
  return loaded;
}

void BM_ReadFrame(benchmark::State& state) {
  const Loaded& l = room();
  const ssgi::RoleMask roles = ssgi::make_plan(l.seq, {}).roles;
  for (auto _ : state) benchmark::DoNotOptimize(ssgi::read_gbuffer(l.seq, 1, roles, l.in));
}

// Indirect light with the given rays and bounces, denoise off or on; threads from the range.
void BM_IndirectLight(benchmark::State& state) {
  const Loaded& l = room();
  ssgi::GiSettings s;
  s.rays = static_cast<int>(state.range(0));
  s.bounces = static_cast<int>(state.range(1));
  s.denoise = state.range(2) ? ssgi::DenoiseMode::kPyramid : ssgi::DenoiseMode::kNone;
  const ssgi::ThreadLimit threads(static_cast<int>(state.range(3)));
  const ssgi::Pipeline pipeline(l.seq, s);
  for (auto _ : state) benchmark::DoNotOptimize(pipeline.indirect_light(l.g));
  state.counters["rays/s"] = benchmark::Counter(
      static_cast<double>(l.g.width()) * l.g.height() * s.rays, benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_ReadFrame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IndirectLight)
    ->ArgNames({"rays", "bounces", "denoise", "threads"})
    ->Args({8, 1, 0, 1})
    ->Args({8, 1, 0, 2})
    ->Args({8, 8, 0, 2})
    ->Args({8, 8, 1, 2})
    ->Args({32, 8, 1, 2})
    ->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  if (!std::filesystem::exists(std::string(SSGI_SHARED_DATA_DIR) + "/room/room.0001.exr")) {
    std::fprintf(stderr, "bench_pipeline: needs ../shared/data/room beside the repository\n");
    return 1;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
