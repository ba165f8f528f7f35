// ssgi reference: the Embree reference over a sequence, written as `ssgi run` writes its output
// so that the two compare channel for channel (ssgi compare).
#include <cstdio>
#include <string>

#include "commands.h"
#include "progress.h"
#include "run_options.h"
#include "ssgi/error.h"

namespace ssgi_cli {
namespace {

constexpr int kDefaultSpp = 256;
constexpr int kMaxSpp = 4096;  // the pipeline's limit on rays per pixel, as --spp checks

void print_help() {
  std::printf(
      "usage: ssgi reference INPUT -o OUTPUT [--spp N] [options]\n\n"
      "Traces the converged answer to the screen-space problem with Embree: N cosine-weighted\n"
      "rays per pixel against the depth buffer's mesh (the same surface model, misses and\n"
      "bounces as ssgi run; --miss extend acts as env). Writes indirect.{R,G,B}, gi.{R,G,B}\n"
      "and the composite R,G,B,A like ssgi run, to measure it with ssgi compare.\n\n"
      "reference:\n"
      "  --spp N               rays per pixel and bounce, 1 to %d (default %d); --rays and\n"
      "                        --max-steps do not apply\n"
      "  --denoise MODE        none (default here) or pyramid\n"
      "  --temporal MODE       none (default here), ema[:ALPHA] or window[:K]\n\n%s",
      kMaxSpp, kDefaultSpp, common_options_help());
}

}  // namespace

int run_reference(int argc, char** argv) {
  CommonOptions o = parse_common_options(argc, argv, /*need_output=*/true);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  if (o.given.count("rays")) ssgi::throw_usage("ssgi reference takes --spp, not --rays");
  ssgi::GiSettings& gi = o.run.gi;
  gi.tracer = ssgi::Tracer::kReference;
  gi.rays = o.spp > 0 ? o.spp : kDefaultSpp;
  // The reference is each frame's converged answer: a denoiser or a temporal filter would only
  // add its own bias.
  if (!o.given.count("denoise")) gi.denoise = ssgi::DenoiseMode::kNone;
  if (!o.given.count("temporal")) gi.temporal = ssgi::TemporalMode::kNone;
  return run_with_progress(o);
}

}  // namespace ssgi_cli
