// The README's library example, built against an installed ssgi: what `ssgi run` writes, from a
// program, through the sequence processor (run_sequence). Fails unless every frame is written.
#include <cstdio>

#include "ssgi/run.h"
#include "ssgi/settings.h"
#include "ssgi/threads.h"
#include "ssgi/version.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr,
                 "usage: run_sequence INPUT OUTPUT (e.g. shot.####.exr out/shot.####.exr)\n");
    return 2;
  }
  const ssgi::ThreadLimit threads(0);  // the scheduler's allocation, else the machine's CPUs
  ssgi::RunOptions options;
  options.input.pattern = argv[1];  // every frame on disk, or a range: shot.1-50#.exr
  options.output = argv[2];
  ssgi::apply_preset("draft", &options.gi);
  ssgi::RunCallbacks callbacks;
  callbacks.on_frame = [](const ssgi::FrameReport& f, int done, int total) {
    std::printf("%d/%d: %s %s\n", done, total, f.output.c_str(),
                f.ok ? "written" : f.error.c_str());
  };
  try {
    const ssgi::RunReport report = ssgi::run_sequence(options, callbacks);
    std::printf("ssgi %s: %d of %d frames failed\n", ssgi::version(), report.failed(),
                report.total);
    return report.total > 0 && report.failed() == 0 ? 0 : 1;
  } catch (const ssgi::Error& e) {  // the whole run: bad options, no frames, over --max-memory
    std::fprintf(stderr, "%s: %s\n", e.file().c_str(), e.what());
    return 1;
  }
}
