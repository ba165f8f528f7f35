#include "frame_source.h"

#include <algorithm>

#include "ssgi/error.h"
#include "ssgi/log.h"
#include "temporal.h"

namespace ssgi::detail {
namespace {

// The EMA's pre-roll: its head start's influence on the first written frame stays below this
// fraction of the largest indirect value (see ema_preroll_frames).
constexpr double kEmaPrerollBound = 1e-3;

// What the temporal stage reads of a neighbour: its geometry, camera and motion; the passes
// only the composite needs are left out.
std::shared_ptr<const GBuffer> geometry_of(const GBuffer& g) {
  auto out = std::make_shared<GBuffer>();
  out->path = g.path;
  out->frame = g.frame;
  out->display_window = g.display_window;
  out->data_window = g.data_window;
  out->camera = g.camera;
  out->depth = g.depth;
  out->normal = g.normal;
  out->motion_prev = g.motion_prev;
  out->motion_next = g.motion_next;
  return out;
}

}  // namespace

FrameSource::FrameSource(const SequenceInfo& sequence, const InputOptions& options,
                         const Pipeline& pipeline)
    : seq_(sequence), options_(options), pipeline_(pipeline) {}

FrameSource::Lit FrameSource::light(int frame) const {
  auto g = std::make_shared<GBuffer>(read_gbuffer(seq_, frame, pipeline_.plan().roles, options_));
  Image indirect = pipeline_.indirect_light(*g);
  return {std::move(g), std::move(indirect)};
}

int FrameSource::previous_on_disk(int frame) const {
  const auto& disk = seq_.frames_on_disk;
  const auto it = std::lower_bound(disk.begin(), disk.end(), frame);
  return it == disk.begin() ? frame : *std::prev(it);
}

FrameSource::Result FrameSource::get(int frame) {
  switch (pipeline_.plan().temporal) {
    case TemporalMode::kWindow:
      return window(frame);
    case TemporalMode::kEma:
      return ema(frame);
    case TemporalMode::kNone:
      break;
  }
  Lit lit = light(frame);
  return {std::move(lit.g), std::move(lit.indirect)};
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
      it->second.g =
          std::make_shared<GBuffer>(read_gbuffer(seq_, f, pipeline_.plan().roles, options_));
      it->second.full = true;
    }
    if (it == ring_.end()) {
      if (f == frame) {
        it = ring_.emplace(f, light(f)).first;  // the frame's own failure throws
      } else {
        try {
          it = ring_.emplace(f, light(f)).first;
        } catch (const Error& e) {
          log_warning((e.file().empty() ? seq_.pattern.path_for(f) : e.file()) + ": " + e.what() +
                      "; left out of the temporal window");
          continue;
        }
      }
    }
    if (f == frame) center = static_cast<int>(frames.size());
    frames.push_back(it->second.g.get());
    indirect.push_back(&it->second.indirect);
  }
  Lit& own = ring_.at(frame);
  Result result{own.g, temporal_window(frames, indirect, center, k)};
  // From now on the frame is only a neighbour (the caller holds the whole G-buffer for the
  // composite): keep what reprojection reads, so that the ring holds the passes of the frames
  // still to be written only.
  own.g = geometry_of(*own.g);
  own.full = false;
  return result;
}

FrameSource::Result FrameSource::ema(int frame) {
  const float alpha = pipeline_.settings().ema_alpha;
  // Continue the running average when the last step was the previous frame on disk; otherwise
  // start over early enough that the head start no longer matters (the pre-roll).
  if (!(ema_valid_ && ema_frame_ == previous_on_disk(frame))) {
    ema_valid_ = false;
    const int preroll = ema_preroll_frames(alpha, kEmaPrerollBound);
    for (int f : seq_.frames_on_disk) {
      if (f < frame - preroll || f >= frame) continue;
      try {
        Lit lit = light(f);
        ema_out_ = ema_valid_ && ema_frame_ == previous_on_disk(f)
                       ? temporal_ema(*lit.g, lit.indirect, *ema_g_, ema_out_, alpha)
                       : std::move(lit.indirect);
        ema_g_ = std::move(lit.g);
        ema_frame_ = f;
        ema_valid_ = true;
      } catch (const Error& e) {
        log_warning((e.file().empty() ? seq_.pattern.path_for(f) : e.file()) + ": " + e.what() +
                    "; the running average starts again after it");
        ema_valid_ = false;
      }
    }
  }
  Lit lit = light(frame);
  Image out = ema_valid_ && ema_frame_ == previous_on_disk(frame)
                  ? temporal_ema(*lit.g, lit.indirect, *ema_g_, ema_out_, alpha)
                  : std::move(lit.indirect);
  ema_g_ = lit.g;
  ema_out_ = out;
  ema_frame_ = frame;
  ema_valid_ = true;
  return {std::move(lit.g), std::move(out)};
}

std::size_t FrameSource::bytes_held() const {
  std::size_t bytes = ema_out_.bytes() + (ema_g_ ? ema_g_->bytes() : 0);
  for (const auto& [f, lit] : ring_) bytes += lit.g->bytes() + lit.indirect.bytes();
  return bytes;
}

}  // namespace ssgi::detail
