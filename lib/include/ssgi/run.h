// A whole `ssgi run`: read, process and write every requested frame.
#pragma once

#include <string>

#include "ssgi/error.h"
#include "ssgi/io.h"
#include "ssgi/plan.h"
#include "ssgi/settings.h"

namespace ssgi {

// Everything a run takes: the input, the output and how to write it, the GI settings. Each
// field is an option of `ssgi run` (man ssgi-run).
struct RunOptions {
  InputOptions input;
  std::string output;   // -o, e.g. "out/shot.####.exr"; empty: none written (on_result only)
  std::string preview;  // --preview, e.g. "prev.####.png": each composite for display; empty: none
  WriteOptions write;
  GiSettings gi;
  bool fail_fast = false;      // --fail-fast: stop at the first frame that fails
  bool skip_existing = false;  // --skip-existing: keep a whole output made with these settings
  bool no_clobber = false;     // --no-clobber: refuse a run that would overwrite a file
  // --max-memory, else the scheduler's: the fastest plan whose estimated peak fits, else none
  // (refused before anything is computed); no limit: the least memory.
  MemoryLimit memory_limit;
  int frames_in_flight = 0;  // --frames-in-flight: 1 to 3; 0: as the memory limit fits
};

// Reads, lights and writes every frame of the input, a few frames at once as the memory limit
// allows. Errors that concern the whole run (bad options, a pattern matching nothing, an output
// that would overwrite an input, or with no_clobber one that exists) are thrown before any frame
// is written; an error in one frame is recorded in its report and the other frames go on.
RunReport run_sequence(const RunOptions& options, const RunCallbacks& callbacks = {});

}  // namespace ssgi
