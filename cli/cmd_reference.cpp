// ssgi reference: the Embree reference over a sequence, written as `ssgi run` writes its output
// so that the two compare channel for channel (ssgi compare).
#include <cstdio>
#include <string>

#include "commands.h"
#include "options/run_options.h"
#include "progress.h"
#include "ssgi/error.h"

namespace ssgi_cli {
namespace {

void print_help() {
  std::printf(
      "usage: ssgi reference INPUT -o OUTPUT [--spp N] [options]\n\n"
      "Traces the converged answer to the screen-space problem with Embree: N\n"
      "cosine-weighted rays per pixel against the depth buffer's mesh (the surface\n"
      "model, misses and bounces of ssgi run; --miss extend acts as env). Writes\n"
      "indirect.{R,G,B}, gi.{R,G,B} and the composite R,G,B,A like ssgi run, to\n"
      "measure it with ssgi compare.\n\n%s",
      options_help(kReferenceCommand).c_str());
}

}  // namespace

int run_reference(int argc, char** argv) {
  // Its defaults (subcommand_defaults): the Embree tracer, no denoiser, no temporal stage.
  const CommonOptions o = parse_common_options(kReferenceCommand, argc, argv, /*need_output=*/true);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  return run_with_progress(o);
}

}  // namespace ssgi_cli
