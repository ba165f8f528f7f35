#include "frame_source.h"

#include <algorithm>
#include <chrono>

#include "ssgi/error.h"
#include "ssgi/log.h"
#include "temporal.h"

namespace ssgi::detail {
namespace {

// The EMA's pre-roll: its head start's influence on the first written frame stays below this
// fraction of the largest indirect value (see ema_preroll_frames).
constexpr double kEmaPrerollBound = 1e-3;

// Adds the wall time of its life, in milliseconds, to *total.
class StopWatch {
 public:
  explicit StopWatch(double* total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~StopWatch() {
    *total_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
                   .count();
  }

 private:
  double* total_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace

FrameSource::FrameSource(const SequenceInfo& sequence, const InputOptions& options,
                         const Pipeline& pipeline)
    : seq_(sequence), options_(options), pipeline_(pipeline) {}

GBuffer FrameSource::read(int frame) const {
  const StopWatch watch(&read_ms_);
  return read_gbuffer(seq_, frame, pipeline_.plan().roles, options_, &pipeline_.color());
}

FrameSource::Lit FrameSource::light(int frame) const {
  auto g = std::make_shared<GBuffer>(read(frame));
  const StopWatch watch(&gi_ms_);
  Pipeline::TracedLight traced = pipeline_.trace_light(*g);
  return {std::move(g), std::move(traced)};
}

Image FrameSource::finish(const GBuffer& g, const Image& grid_light) const {
  const StopWatch watch(&gi_ms_);
  return pipeline_.finish_light(g, grid_light);
}

FrameSource::Result FrameSource::get(int frame) {
  read_ms_ = gi_ms_ = 0;
  switch (pipeline_.plan().temporal) {
    case TemporalMode::kWindow:
      return window(frame);
    case TemporalMode::kEma:
      return ema(frame);
    case TemporalMode::kNone:
      break;
  }
  auto g = std::make_shared<GBuffer>(read(frame));
  const StopWatch watch(&gi_ms_);
  Image indirect = pipeline_.indirect_light(*g);
  return {std::move(g), std::move(indirect)};
}

FrameSource::Result FrameSource::window(int frame) {
  const int k = pipeline_.settings().temporal_radius;
  // Drop what this window does not use; frames already lit stay for the next one.
  for (auto it = ring_.begin(); it != ring_.end();)
    it = std::abs(it->first - frame) > k ? ring_.erase(it) : std::next(it);
  std::vector<const GBuffer*> frames;
  std::vector<const Image*> indirect;
  int center = -1;
  for (int f : seq_.frames_on_disk) {
    if (std::abs(f - frame) > k) continue;
    auto it = ring_.find(f);
    if (it != ring_.end() && f == frame && !it->second.full) {
      // Composited before and trimmed (an output order that comes back to a frame): read its
      // passes again, its light is kept.
      it->second.g = std::make_shared<GBuffer>(read(f));
      it->second.full = true;
    }
    if (it == ring_.end()) {
      if (f == frame) {
        it = ring_.emplace(f, light(f)).first;  // the frame's own failure throws
      } else {
        if (unreadable_.count(f)) continue;  // warned about once, not tried again
        try {
          it = ring_.emplace(f, light(f)).first;
        } catch (const Error& e) {
          log_warning((e.file().empty() ? seq_.pattern.path_for(f) : e.file()) + ": " + e.what() +
                      "; left out of the temporal window");
          unreadable_.insert(f);
          continue;
        }
      }
    }
    if (f == frame) center = static_cast<int>(frames.size());
    frames.push_back(&it->second.traced.grid);
    indirect.push_back(&it->second.traced.light);
  }
  Lit& own = ring_.at(frame);
  Image filtered;
  {
    const StopWatch watch(&gi_ms_);
    filtered = temporal_window(frames, indirect, center, k);
  }
  Result result{own.g, finish(*own.g, filtered)};
  // From now on the frame is only a neighbour (the caller holds the whole G-buffer for the
  // composite): reprojection reads its trace grid, so the ring holds the passes of the frames
  // still to be written only.
  own.g.reset();
  own.full = false;
  return result;
}

FrameSource::Result FrameSource::ema(int frame) {
  const float alpha = pipeline_.settings().ema_alpha;
  const std::vector<int>& disk = seq_.frames_on_disk;
  const int target =
      static_cast<int>(std::lower_bound(disk.begin(), disk.end(), frame) - disk.begin());
  // The pre-roll counts frames on disk (averaging steps), not frame numbers: a shot on twos
  // needs as many steps as one on ones.
  const int preroll =
      std::min(ema_preroll_frames(alpha, kEmaPrerollBound), static_cast<int>(disk.size()));
  // Go on from the last frame stepped when it comes before this one within the pre-roll (the
  // same running average a whole run computes); otherwise start over, `preroll` frames on disk
  // earlier, so that the head start no longer matters.
  int start;
  if (ema_valid_ && ema_index_ < target && target - ema_index_ <= preroll) {
    start = ema_index_ + 1;
  } else {
    ema_valid_ = false;
    start = std::max(0, target - preroll);
  }
  for (int i = start; i < target; ++i) {
    if (unreadable_.count(disk[i])) {
      ema_valid_ = false;  // warned about once, not tried again
      continue;
    }
    try {
      ema_step(i, light(disk[i]));
    } catch (const Error& e) {
      log_warning((e.file().empty() ? seq_.pattern.path_for(disk[i]) : e.file()) + ": " + e.what() +
                  "; the running average starts again after it");
      unreadable_.insert(disk[i]);
      ema_valid_ = false;
    }
  }
  Lit lit = light(frame);
  std::shared_ptr<const GBuffer> g = lit.g;
  ema_step(target, std::move(lit));
  Image indirect = finish(*g, ema_out_);
  return {std::move(g), std::move(indirect)};
}

void FrameSource::ema_step(int index, Lit lit) {
  const StopWatch watch(&gi_ms_);
  const bool follows = ema_valid_ && ema_index_ == index - 1;
  ema_out_ = follows ? temporal_ema(lit.traced.grid, lit.traced.light, *ema_g_, ema_out_,
                                    pipeline_.settings().ema_alpha)
                     : std::move(lit.traced.light);
  // The next step reprojects from this frame: its trace grid is all it reads.
  ema_g_ = std::make_shared<GBuffer>(std::move(lit.traced.grid));
  ema_index_ = index;
  ema_valid_ = true;
}

}  // namespace ssgi::detail
