// Running a sequence with progress lines and an exit code: what `ssgi run` and
// `ssgi reference` share once their options are parsed.
#pragma once

#include "options/run_options.h"

namespace ssgi_cli {

// Sets up logging and the thread limit from `options`, runs the pipeline over the sequence
// with a line per frame on stderr (one updating line on a terminal) and returns the exit code:
// 0 when every frame was written, 1 when some failed, else the code of the first failure.
int run_with_progress(const CommonOptions& options);

}  // namespace ssgi_cli
