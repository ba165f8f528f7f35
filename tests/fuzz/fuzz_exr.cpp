// libFuzzer target: arbitrary bytes as an EXR frame, through what `ssgi run` does with one —
// probe the sequence and its layout, read the G-buffer (any camera the header gives, else a
// --fov one), and on a frame of at most 64 x 64 pixels trace, bounce, denoise, composite and
// write it with passthrough. An ssgi::Error is a refusal (fine); a crash, a sanitizer report, a
// leak, a hang or a non-finite value in ssgi's layers is a finding.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "plan.h"
#include "ssgi/error.h"
#include "ssgi/log.h"
#include "ssgi/pipeline.h"
#include "ssgi/settings.h"

namespace {

std::string scratch_dir() {
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    const std::string d =
        std::string(tmp && *tmp ? tmp : "/tmp") + "/ssgi_fuzz_exr." + std::to_string(getpid());
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

void check_finite(const ssgi::Image& image) {
  for (float v : image.data())
    if (!std::isfinite(v)) {
      std::fprintf(stderr, "non-finite value %g in ssgi's layers\n", v);
      std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ssgi::set_log_handler([](ssgi::LogLevel, const std::string&) {});
  ssgi::set_io_threads(1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string dir = scratch_dir();
  const std::string in_path = dir + "/in.0001.exr";
  {
    std::ofstream out(in_path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    ssgi::InputOptions in;
    in.pattern = dir + "/in.####.exr";
    if (size % 2) in.camera.hfov_deg = 50;  // else the header's camera, if it has one
    const ssgi::SequenceInfo seq = ssgi::open_sequence(in);
    ssgi::GiSettings gi;
    ssgi::apply_preset("draft", &gi);
    gi.bounces = 2;
    gi.temporal = ssgi::TemporalMode::kNone;
    const ssgi::Pipeline pipeline(seq, gi);
    const ssgi::GBuffer g = ssgi::read_gbuffer(seq, seq.frames.front(), pipeline.plan().roles, in);
    if (static_cast<long>(g.width()) * g.height() > 64 * 64) return 0;
    ssgi::FrameResult result = pipeline.composite(g, pipeline.indirect_light(g));
    check_finite(result.indirect);
    check_finite(result.gi);
    check_finite(result.composite);
    ssgi::WriteOptions write;
    ssgi::write_frame(dir + "/out.0001.exr", g,
                      {{"", &result.composite, {"R", "G", "B", "A"}},
                       {"indirect", &result.indirect, {"R", "G", "B"}},
                       {"gi", &result.gi, {"R", "G", "B"}}},
                      write);
  } catch (const ssgi::Error&) {
  }
  return 0;
}
