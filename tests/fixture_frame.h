// Loading one frame of a testdata/ fixture as the pipeline would, for the library tests.
#pragma once

#include <string>

#include "io/frame_reader.h"
#include "plan.h"
#include "ssgi/pipeline.h"

namespace ssgi::test_fixtures {

struct FixtureFrame {
  SequenceInfo seq;
  GBuffer g;
};

// `pattern` relative to testdata/; the roles `settings` plans to read; the sequence's first
// frame when `frame` is not given.
inline FixtureFrame load_fixture(const std::string& pattern, const GiSettings& settings,
                                 int frame = -1) {
  InputOptions in;
  in.pattern = std::string(SSGI_TESTDATA_DIR) + "/" + pattern;
  FixtureFrame f;
  f.seq = open_sequence(in);
  f.g = read_gbuffer(f.seq, frame < 0 ? f.seq.frames.front() : frame,
                     make_plan(f.seq, settings).roles, in);
  return f;
}

}  // namespace ssgi::test_fixtures
