// ssgi reference: the Embree reference over a sequence, written as `ssgi run` writes its output
// so that the two compare channel for channel (ssgi compare).
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "commands.h"
#include "progress.h"
#include "run_options.h"
#include "ssgi/error.h"

namespace ssgi_cli {
namespace {

constexpr int kDefaultSpp = 256;
constexpr int kMaxSpp = 4096;  // the pipeline's limit on rays per pixel

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

// Whether `args` (before any "--") hold option `name` as "--name" or "--name=VALUE".
bool has_option(const std::vector<char*>& args, const std::string& name) {
  const std::string flag = "--" + name;
  for (const char* a : args) {
    if (std::strcmp(a, "--") == 0) break;
    if (a == flag || std::strncmp(a, (flag + "=").c_str(), flag.size() + 1) == 0) return true;
  }
  return false;
}

int parse_spp(const char* text) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || v < 1 || v > kMaxSpp)
    ssgi::throw_usage(std::string("--spp: '") + text + "' is not an integer in [1, " +
                      std::to_string(kMaxSpp) + "]");
  return static_cast<int>(v);
}

// --spp is this command's own option and the rest are `ssgi run`'s: takes "--spp N" and
// "--spp=N" out of `args` and returns N, or kDefaultSpp when absent.
int take_spp(std::vector<char*>* args) {
  int spp = kDefaultSpp;
  for (std::size_t i = 1; i < args->size();) {
    const char* a = (*args)[i];
    if (std::strcmp(a, "--") == 0) break;
    if (std::strcmp(a, "--spp") == 0) {
      if (i + 1 >= args->size()) ssgi::throw_usage("option '--spp' needs a value");
      spp = parse_spp((*args)[i + 1]);
      args->erase(args->begin() + i, args->begin() + i + 2);
    } else if (std::strncmp(a, "--spp=", 6) == 0) {
      spp = parse_spp(a + 6);
      args->erase(args->begin() + i);
    } else {
      ++i;
    }
  }
  return spp;
}

}  // namespace

int run_reference(int argc, char** argv) {
  std::vector<char*> args(argv, argv + argc);
  const int spp = take_spp(&args);
  if (has_option(args, "rays")) ssgi::throw_usage("ssgi reference takes --spp, not --rays");
  const bool denoise_given = has_option(args, "denoise");
  const bool temporal_given = has_option(args, "temporal");
  args.push_back(nullptr);  // getopt_long reads argv[argc]
  CommonOptions o = parse_common_options(static_cast<int>(args.size()) - 1, args.data(),
                                         /*need_output=*/true);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  // Provenance names the whole invocation, --spp included.
  o.command_line = "ssgi";
  for (int i = 0; i < argc; ++i) o.command_line += std::string(" ") + argv[i];
  ssgi::GiSettings& gi = o.run.gi;
  gi.tracer = ssgi::Tracer::kReference;
  gi.rays = spp;
  // The reference is each frame's converged answer: a denoiser or a temporal filter would only
  // add its own bias.
  if (!denoise_given) gi.denoise = ssgi::DenoiseMode::kNone;
  if (!temporal_given) gi.temporal = ssgi::TemporalMode::kNone;
  return run_with_progress(o);
}

}  // namespace ssgi_cli
