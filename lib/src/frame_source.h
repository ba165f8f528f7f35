// The frames a run needs, each read and lit once: the frame loop asks for an output frame's
// G-buffer and (temporally filtered) indirect light, and this keeps the ring of neighbours the
// temporal stage reads — 2K + 1 frames for the window, the previous frame for the EMA.
#pragma once

#include <map>
#include <memory>
#include <set>

#include "ssgi/gbuffer.h"
#include "ssgi/io.h"
#include "ssgi/pipeline.h"

namespace ssgi::detail {

class FrameSource {
 public:
  FrameSource(const SequenceInfo& sequence, const InputOptions& options, const Pipeline& pipeline);

  // Output frame `frame`: its G-buffer and its indirect light after the temporal stage. Reads
  // and lights the neighbours the stage needs (frames on disk within the window, or the EMA's
  // pre-roll), dropping what no later frame needs. A neighbour that cannot be read is left out
  // with a warning; the frame's own failure throws its ssgi::Error.
  struct Result {
    std::shared_ptr<const GBuffer> g;
    Image indirect;
  };
  Result get(int frame);

  // Milliseconds the last get() spent reading inputs (decoding and converting) and computing
  // light (trace, bounces, denoise, temporal), over every frame it read for the window.
  double read_ms() const { return read_ms_; }
  double gi_ms() const { return gi_ms_; }

 private:
  struct Lit {
    std::shared_ptr<const GBuffer> g;  // the frame, for the composite and the denoiser
    Pipeline::TracedLight traced;      // its light on the trace grid, before temporal filtering
    bool full = true;  // false once the frame's passes are dropped (the grid is what
                       // reprojection reads)
  };
  Lit light(int frame) const;
  // The traced light carried to the frame's resolution (Pipeline::finish_light), timed.
  Image finish(const GBuffer& g, const Image& grid_light) const;
  Result window(int frame);
  Result ema(int frame);
  // One step of the running average over the frame at `index` in frames_on_disk.
  void ema_step(int index, Lit lit);

  GBuffer read(int frame) const;

  mutable double read_ms_ = 0, gi_ms_ = 0;
  const SequenceInfo& seq_;
  const InputOptions& options_;
  const Pipeline& pipeline_;
  std::map<int, Lit> ring_;   // window: frames on disk around the last output frame
  std::set<int> unreadable_;  // neighbours that failed to read: warned about once, left out
  // EMA: the last frame stepped (its index in frames_on_disk) and its filtered output.
  int ema_index_ = 0;
  bool ema_valid_ = false;
  std::shared_ptr<const GBuffer> ema_g_;  // the last frame stepped's trace grid
  Image ema_out_;                         // its filtered light on the grid
};

}  // namespace ssgi::detail
