// What the pipeline's tests share: a fixture frame loaded and run through the pipeline, the
// tracers they run, and a blank frame to draw analytic scenes into.
#pragma once

#include <string>

#include "fixture_frame.h"
#include "io/frame_reader.h"
#include "ssgi/pipeline.h"

namespace ssgi::pipeline_test {

using Frame = test_fixtures::FixtureFrame;

inline Frame load(const std::string& pattern, const GiSettings& settings) {
  return test_fixtures::load_fixture(pattern, settings);
}

inline FrameResult run(const Frame& f, const GiSettings& settings) {
  const Pipeline pipeline(f.seq, settings);
  return pipeline.composite(f.g, pipeline.indirect_light(f.g));
}

// Every tracer follows the same surface model and miss rules: the known answers hold for each.
inline const Tracer kTracers[] = {Tracer::kSlices, Tracer::kScreenSpace};
inline const char* tracer_name(Tracer t) { return t == Tracer::kSlices ? "slices" : "march"; }

// Settings that take the tracers to their converged answer on a small analytic scene: every
// pixel traced, many slices, rays and samples, no denoise, no temporal stage.
inline GiSettings converged_settings() {
  GiSettings s;
  s.denoise = DenoiseMode::kNone;
  s.temporal = TemporalMode::kNone;
  s.trace_scale = 1;
  s.slices = 16;
  s.rays = 64;
  s.max_steps = 64;
  return s;
}

// The plane fixture's frame emptied for an analytic scene drawn into it: a centred camera of
// `hfov` degrees (no world transform: camera space is world space), depth `depth`, no normals,
// albedo 0.5, no light.
inline Frame blank_scene(const GiSettings& settings, double hfov, float depth) {
  Frame f = load("plane/plane.0001.exr", settings);
  GBuffer& g = f.g;
  const int w = g.width(), h = g.height();
  g.camera = camera_from_fov(hfov, g.display_window);
  g.depth = Image(w, h, 1, depth);
  g.normal = Image(w, h, 3);
  g.albedo = Image(w, h, 3, 0.5f);
  g.direct = Image(w, h, 3);
  if (!g.emission.empty()) g.emission = Image(w, h, 3);
  return f;
}

}  // namespace ssgi::pipeline_test
