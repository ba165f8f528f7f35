// A whole `ssgi run`: read, process and write every requested frame.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ssgi/error.h"
#include "ssgi/io.h"
#include "ssgi/pipeline.h"
#include "ssgi/report.h"
#include "ssgi/settings.h"

namespace ssgi {

struct RunOptions {
  InputOptions input;
  // Output pattern, e.g. "out/shot.####.exr"; empty: no frame is written (the results go to
  // RunCallbacks::on_result only).
  std::string output;
  // --preview: each frame's composite through the display and view, e.g. "prev.####.png"
  // (.png or .jpg), the size of the display window; empty: none.
  std::string preview;
  WriteOptions write;
  GiSettings gi;
  bool fail_fast = false;  // --fail-fast: stop at the first frame that fails
  // --skip-existing: a frame whose output exists, reads whole and was made by this version of
  // ssgi with these settings (its header says) is not made again.
  bool skip_existing = false;
  // --no-clobber: refuse the run, before any frame is computed, when it would overwrite a file.
  bool no_clobber = false;
  // --max-memory, else the scheduler's (scheduler_memory_limit): the run takes the fastest plan
  // whose estimated peak (estimate_run_memory) fits it, and is refused before anything is
  // computed or written when none does; none: the least memory (pipeline_memory_within).
  MemoryLimit memory_limit;
  // --frames-in-flight: frames read, lit and written at once (1 to 3, the window's frames
  // kept; 0: as the limit fits, pipeline_memory_within), fewer when the memory limit needs it.
  int frames_in_flight = 0;
};

// Runs the pipeline over the sequence: each input decoded to be lit, and while one frame is lit
// the next may be read and the last written (the plan pipeline_memory_within makes for the
// memory limit); its passed-through channels are read from the file again when it is written.
// Errors that concern the whole run (bad options, a
// pattern matching nothing, an output that would overwrite an input, or with no_clobber any
// existing output it would write again) are thrown as ssgi::Error before any frame is written;
// an error in one frame is recorded in its report and the other frames go on.
RunReport run_sequence(const RunOptions& options, const RunCallbacks& callbacks = {});

}  // namespace ssgi
