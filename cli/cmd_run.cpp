// ssgi run: the pipeline over a sequence.
#include <cstdio>

#include "commands.h"
#include "options/run_options.h"
#include "progress.h"
#include "ssgi/error.h"

namespace ssgi_cli {
namespace {

void print_help() {
  std::printf(
      "usage: ssgi run INPUT -o OUTPUT [options]\n\n"
      "Adds screen-space diffuse global illumination to an EXR G-buffer sequence.\n"
      "INPUT and OUTPUT are file names or patterns (shot.####.exr, shot.%%04d.exr,\n"
      "shot.1-50#.exr). Writes indirect.{R,G,B}, gi.{R,G,B} and the composite R,G,B,A.\n\n%s",
      options_help(kRunCommand).c_str());
}

}  // namespace

int run_run(int argc, char** argv) {
  const CommonOptions o = parse_common_options(kRunCommand, argc, argv, /*need_output=*/true);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  return run_with_progress(o);
}

}  // namespace ssgi_cli
