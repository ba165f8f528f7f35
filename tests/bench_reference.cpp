// The Embree reference's throughput on the room sample (Cycles, 320x180): rays per second, and
// per core, for 1 and 2 threads. Each iteration builds the frame's scene and traces every ray, as
// `ssgi reference` does per frame; spp 1 shows what the scene build costs on its own.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "io/frame_reader.h"
#include "plan.h"
#include "reference/reference.h"
#include "ssgi/pipeline.h"
#include "ssgi/threads.h"

namespace {

const std::string kRoom = std::string(SSGI_SHARED_DATA_DIR) + "/room";

void BM_TraceReference(benchmark::State& state) {
  if (!std::filesystem::exists(kRoom + "/room.0001.exr")) {
    state.SkipWithError(("no sample data in " + kRoom).c_str());
    return;
  }
  const int threads = static_cast<int>(state.range(0));
  ssgi::GiSettings settings;
  settings.tracer = ssgi::Tracer::kReference;
  settings.rays = static_cast<int>(state.range(1));
  ssgi::InputOptions in;
  in.pattern = kRoom + "/room.####.exr";
  in.frames = "1";
  const ssgi::SequenceInfo seq = ssgi::open_sequence(in);
  const ssgi::GBuffer g = ssgi::read_gbuffer(seq, 1, ssgi::make_plan(seq, settings).roles, in);
  std::size_t surface_pixels = 0;
  for (float z : g.depth.data()) surface_pixels += std::isfinite(z) ? 1 : 0;

  const ssgi::ThreadLimit limit(threads);
  const ssgi::detail::Environment black;
  const ssgi::detail::MissModel misses(g, settings.miss, black);
  for (auto _ : state) {
    const ssgi::detail::RayHits hits = ssgi::detail::trace_reference(g, settings, misses);
    benchmark::DoNotOptimize(hits.hit.data());
  }
  const double rays = static_cast<double>(surface_pixels) * settings.rays;
  state.counters["rays/s"] =
      benchmark::Counter(rays, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["rays/s/core"] =
      benchmark::Counter(rays / threads, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TraceReference)
    ->ArgNames({"threads", "spp"})
    ->Args({1, 256})
    ->Args({2, 256})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
