#include "sequence_processor.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <deque>
#include <exception>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <utility>

#include "frame_stages.h"
#include "gi/continuation.h"
#include "gi/temporal.h"
#include "io/guide.h"
#include "io/sequence.h"
#include "io/views.h"
#include "log.h"
#include "parallel.h"
#include "ssgi/error.h"

namespace ssgi::detail {
namespace {

// The EMA's pre-roll: its head start's influence on the first written frame stays below this
// fraction of the largest indirect value (see ema_preroll_frames).
constexpr double kEmaPrerollBound = 1e-3;

constexpr int kNoFrame = INT_MIN;

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// One step of a run: at most one input decoded and lit, then perhaps one frame finished. The
// steps are planned before the run from the frames asked for and the temporal stage alone, so
// that reading can go ahead of lighting.
struct Step {
  int read = kNoFrame;   // the frame on disk decoded and lit at this step
  int output = -1;       // the index (in the frames asked for) of the frame these steps serve
  bool restart = false;  // EMA: the running average starts again at `read`
  bool finish = false;   // the frame `output` is finished (or reused) after this step
  bool reread = false;   // `read` (the frame `output`) decoded again to be finished, not lit
};

// The temporal stage's shot: the frames on disk, cut at their gaps (find_frame_gaps) into parts
// that it treats as shots of their own. Whatever frames a run writes, the parts are the same.
class ShotParts {
 public:
  explicit ShotParts(const std::vector<int>& frames_on_disk) : disk_(frames_on_disk) {
    const std::vector<std::pair<int, int>> gaps = find_frame_gaps(disk_).gaps;
    std::size_t gap = 0;
    for (int i = 0; i < static_cast<int>(disk_.size()); ++i) {
      const bool after_gap = gap < gaps.size() && gaps[gap].second < disk_[i];
      if (after_gap) ++gap;
      part_begin_.push_back(i == 0 || after_gap ? i : part_begin_.back());
    }
  }

  // The index in the frames on disk of `frame`, which is one of them.
  int index(int frame) const {
    return static_cast<int>(std::lower_bound(disk_.begin(), disk_.end(), frame) - disk_.begin());
  }
  // The index of the first frame of the part that holds the frame at `index`.
  int part_begin(int index) const { return part_begin_[index]; }
  // Whether frames `a` and `b` on disk lie in one part: no gap between them.
  bool together(int a, int b) const { return part_begin(index(a)) == part_begin(index(b)); }
  // Whether frame `f` on disk is in the window of radius `radius` around frame `n` on disk:
  // within `radius` frame numbers of it, and no gap between them (a gap ends the shot).
  bool in_window(int f, int n, int radius) const {
    return std::abs(f - n) <= radius && together(f, n);
  }

 private:
  const std::vector<int>& disk_;
  std::vector<int> part_begin_;  // per frame on disk
};

// The steps of a run, mirroring what the temporal stage needs: for each frame written, the
// frames on disk within its window that the ring does not hold yet (the ring drops the frames
// outside the window first), then with `read_twice` the frame itself again; or the running
// average's steps up to it (continued from the last frame written when it came shortly before
// in the same part of the shot, else a pre-roll from no earlier than the part's first frame),
// or the frame alone.
std::vector<Step> plan_steps(const SequenceInfo& seq, const ShotParts& parts, TemporalMode mode,
                             int radius, int preroll, const std::vector<char>& reuse,
                             bool read_twice) {
  const std::vector<int>& disk = seq.frames_on_disk;
  std::vector<Step> steps;
  std::set<int> ring;
  int ema_last = -1;
  for (int i = 0; i < static_cast<int>(seq.frames.size()); ++i) {
    const int n = seq.frames[i];
    const std::size_t first = steps.size();
    if (!reuse[i]) {
      switch (mode) {
        case TemporalMode::kNone:
          steps.push_back({n, i});
          break;
        case TemporalMode::kWindow:
          for (auto it = ring.begin(); it != ring.end();)
            it = parts.in_window(*it, n, radius) ? std::next(it) : ring.erase(it);
          for (int f : disk)
            if (parts.in_window(f, n, radius) && ring.insert(f).second) steps.push_back({f, i});
          if (read_twice) {
            Step second{n, i};
            second.reread = true;
            steps.push_back(second);
          }
          break;
        case TemporalMode::kEma: {
          const int target = parts.index(n);
          const int part_begin = parts.part_begin(target);
          // Counted in frames on disk (averaging steps), not frame numbers.
          const bool follows =
              ema_last >= part_begin && ema_last < target && target - ema_last <= preroll;
          const int start = follows ? ema_last + 1 : std::max(part_begin, target - preroll);
          for (int d = start; d <= target; ++d)
            steps.push_back({disk[d], i, !follows && d == start});
          ema_last = target;
          break;
        }
      }
    }
    if (steps.size() == first) steps.push_back({kNoFrame, i});
    steps.back().finish = true;
  }
  return steps;
}

struct FrameError {
  ErrorKind kind = ErrorKind::kInternal;
  std::string file, what;
};

// A G-buffer's description without its planes: what writing a frame reads of it.
GBuffer without_planes(const GBuffer& g) {
  GBuffer out;
  out.path = g.path;
  out.frame = g.frame;
  out.display_window = g.display_window;
  out.data_window = g.data_window;
  out.camera = g.camera;
  out.sanitized = g.sanitized;
  return out;
}

// `image`, covering `from`, cut to `to` (which `from` holds).
Image cut(const Image& image, const Box2i& from, const Box2i& to) {
  if (image.empty()) return Image();
  Image out(to.width(), to.height(), image.channels());
  copy_window(image, from, &out, to);
  return out;
}

// --context: a frame lit over the whole picture, and its results, cut to the input's data
// window, which is all that is written of it.
void cut_to(const Box2i& window, std::shared_ptr<const GBuffer>* frame, FrameResult* result) {
  const GBuffer& g = **frame;
  const Box2i& from = g.data_window;
  GBuffer out = without_planes(g);
  out.data_window = window;
  for (auto [in, cut_out] : {std::pair{&g.depth, &out.depth},
                             {&g.normal, &out.normal},
                             {&g.albedo, &out.albedo},
                             {&g.direct, &out.direct},
                             {&g.emission, &out.emission},
                             {&g.motion_prev, &out.motion_prev},
                             {&g.motion_next, &out.motion_next},
                             {&g.beauty, &out.beauty}})
    *cut_out = cut(*in, from, window);
  for (Image* image : {&result->indirect, &result->gi, &result->composite, &result->coverage})
    *image = cut(*image, from, window);
  *frame = std::make_shared<const GBuffer>(std::move(out));
}

FrameError error_of(const Error& e) { return {e.kind(), e.file(), e.what()}; }

[[noreturn]] void rethrow(const FrameError& e) { throw Error(e.kind, e.file, e.what); }

// Functions run on the thread that called process_sequence, posted from the pipeline's.
class CallerThread {
 public:
  void post(std::function<void()> f) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      tasks_.push_back(std::move(f));
    }
    cv_.notify_one();
  }
  // Runs `f` there and waits for it; its exception comes back here.
  void call(const std::function<void()>& f) {
    std::promise<void> done;
    post([&] {
      try {
        f();
        done.set_value();
      } catch (...) {
        done.set_exception(std::current_exception());
      }
    });
    done.get_future().get();
  }
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    cv_.notify_one();
  }
  // Runs what is posted until close().
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      cv_.wait(lock, [&] { return closed_ || !tasks_.empty(); });
      if (tasks_.empty()) return;
      std::function<void()> f = std::move(tasks_.front());
      tasks_.pop_front();
      lock.unlock();
      f();
      lock.lock();
    }
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> tasks_;
  bool closed_ = false;
};

// What the reading stage hands on: a step and its frame decoded (or why not).
struct Decoded {
  Step step;
  std::optional<InputFrame> frame;
  std::optional<FrameError> error;
  double read_ms = 0;
};

// What the lighting stage hands on: a frame finished (or reused, or failed), or nothing.
struct FinishedFrame {
  int output = -1;  // index in the frames asked for; -1: no frame finished at this step
  bool reused = false;
  std::shared_ptr<const GBuffer> g;
  std::shared_ptr<const DecodedInput> input;
  std::shared_ptr<FrameResult> result;
  std::optional<FrameError> error;
  double read_ms = 0, gi_ms = 0;
  GuideStats guide;
};

GuideStats guide_stats(const GuideReport& r) {
  GuideStats s;
  s.used = true;
  s.known_share = r.known_share;
  s.residual_share = r.residual_share;
  s.detail_kept = r.detail_kept;
  return s;
}

class Processor {
 public:
  Processor(const SequenceJob& job, const RunCallbacks& callbacks)
      : job_(job),
        seq_(*job.sequence),
        stages_(*job.pipeline),
        callbacks_(callbacks),
        mode_(stages_.plan().temporal),
        radius_(stages_.settings().temporal_radius),
        read_twice_(job.read_twice && mode_ == TemporalMode::kWindow),
        parts_(seq_.frames_on_disk) {
    const int preroll =
        mode_ == TemporalMode::kEma
            ? std::min(ema_preroll_frames(stages_.settings().ema_alpha, kEmaPrerollBound),
                       static_cast<int>(seq_.frames_on_disk.size()))
            : 0;
    steps_ = plan_steps(seq_, parts_, mode_, radius_, preroll, job.reuse, read_twice_);
    // The views and the guide cover every frame the run decodes for lighting.
    std::vector<int> read;
    for (const Step& s : steps_)
      if (s.read != kNoFrame && !s.reread) read.push_back(s.read);
    if (stages_.plan().views) check_views_cover(seq_, read);
    if (stages_.plan().guide) check_guide_covers(seq_, read);
    for (int i = 0; i < static_cast<int>(seq_.frames.size()); ++i)
      if (!job.reuse[i]) output_index_[seq_.frames[i]] = i;
  }

  RunReport run() {
    report_.total = static_cast<int>(seq_.frames.size());
    std::exception_ptr failure;
    std::thread worker([&] {
      try {
        pipeline_in_order<Decoded, FinishedFrame>(
            static_cast<int>(steps_.size()), job_.in_flight, [&](int i) { return read(steps_[i]); },
            [&](Decoded d) { return light_and_finish(std::move(d)); },
            [&](FinishedFrame m) { write(std::move(m)); }, [&] { return !stopped_.load(); });
      } catch (...) {
        failure = std::current_exception();
      }
      caller_.close();
    });
    caller_.run();
    worker.join();
    if (failure) std::rethrow_exception(failure);
    if (callback_failure_) std::rethrow_exception(callback_failure_);
    return report_;
  }

 private:
  // Whether frame `f`, read for the frame at `output`, is itself still to be written.
  bool still_to_write(int f, int output) const {
    const auto it = output_index_.find(f);
    return it != output_index_.end() && it->second >= output;
  }

  // Whose times a step's work counts in: the frame it reads when that frame is written, else
  // the frame the step serves (a neighbour outside the frames asked for, a pre-roll frame).
  int owner(const Step& s) const {
    return s.read != kNoFrame && output_index_.count(s.read) ? s.read : seq_.frames[s.output];
  }

  Decoded read(const Step& step) {
    Decoded d;
    d.step = step;
    if (step.read == kNoFrame) return d;
    const auto start = Clock::now();
    const Plan& plan = stages_.plan();
    RoleMask roles = plan.roles;
    bool report = true;
    if (step.reread) {
      // Motion only served the trace grid.
      roles &= ~role_bit(Role::kMotion);
    } else if (read_twice_ && still_to_write(step.read, step.output)) {
      // Lit now, finished from its second reading: what tracing reads, without a warning
      // (the second reading gives it).
      roles &= ~role_bit(Role::kBeauty);
      if (!plan.gather_emission) roles &= ~role_bit(Role::kEmission);
      report = false;
    }
    try {
      d.frame = read_input_frame(seq_, step.read, roles, *job_.input, &stages_.color(), report);
      if (plan.views && !step.reread)
        d.frame->views = read_views(seq_, step.read, *job_.input, &stages_.color());
      if (plan.guide && !step.reread)
        d.frame->guide = read_guide(seq_, step.read, d.frame->g, *job_.input, &stages_.color());
    } catch (const Error& e) {
      d.error = error_of(e);
    } catch (const std::bad_alloc&) {
      d.error = FrameError{ErrorKind::kIO, seq_.pattern.path_for(step.read), "out of memory"};
    }
    d.read_ms = ms_since(start);
    return d;
  }

  // The lighting stage: the frame a step decoded lit for the temporal stage, then, at a step
  // that finishes a frame, that frame finished.
  FinishedFrame light_and_finish(Decoded d) {
    const Step& s = d.step;
    const int n = seq_.frames[s.output];
    const bool made = !job_.reuse[s.output];
    times_[owner(s)].first += d.read_ms;
    const auto start = Clock::now();
    if (mode_ == TemporalMode::kWindow && made)
      for (auto it = ring_.begin(); it != ring_.end();)
        it = parts_.in_window(it->first, n, radius_) ? std::next(it) : ring_.erase(it);
    std::optional<InputFrame> own;        // frame n, when it is read at the step that finishes it
    std::optional<FrameError> own_error;  // why frame n could not be read again
    if (s.reread) {
      if (d.error)
        own_error = d.error;
      else
        own = std::move(d.frame);
    } else if (s.read != kNoFrame) {
      try {
        if (d.error) rethrow(*d.error);
        own = light_for_temporal(s, std::move(*d.frame));
        failed_.erase(s.read);
      } catch (const Error& e) {
        failed(s.read, error_of(e), n);
      } catch (const std::bad_alloc&) {
        failed(s.read, {ErrorKind::kIO, seq_.pattern.path_for(s.read), "out of memory"}, n);
      }
    }
    times_[owner(s)].second += ms_since(start);
    FinishedFrame m;
    if (!s.finish) return m;
    m.output = s.output;
    m.reused = !made;
    if (!made) {
      times_.erase(n);
      return m;
    }
    const auto finish_start = Clock::now();
    try {
      // A frame that could not be lit fails for that reason first.
      if (own_error && !failed_.count(n)) rethrow(*own_error);
      finish(n, std::move(own), &m);
    } catch (const Error& e) {
      m.error = error_of(e);
    } catch (const std::bad_alloc&) {
      m.error = FrameError{ErrorKind::kIO, seq_.pattern.path_for(n), "out of memory"};
    }
    std::pair<double, double>& times = times_[n];
    times.second += ms_since(finish_start);
    m.read_ms = times.first;
    m.gi_ms = times.second;
    times_.erase(n);
    return m;
  }

  // A frame that could not be read or lit: left out of what follows. A neighbour's failure is
  // warned about once (the frame's own failure is its error).
  void failed(int f, const FrameError& e, int n) {
    failed_.emplace(f, e);
    if (mode_ == TemporalMode::kEma) {
      ema_valid_ = false;
      if (f != n)
        log_warning((e.file.empty() ? seq_.pattern.path_for(f) : e.file) + ": " + e.what +
                    "; the running average starts again after it");
    }
  }

  // Lights a decoded frame at step `s`: into the ring (window) or the running average (EMA).
  // Returns it when the step finishes it and it is still needed whole.
  std::optional<InputFrame> light_for_temporal(const Step& s, InputFrame frame) {
    const int n = seq_.frames[s.output];
    if (mode_ == TemporalMode::kNone) return frame;
    const LitViews views = stages_.light_views(frame.views);
    frame.views.clear();
    TracedLight traced = stages_.grid_light(frame.g, &views);
    if (stages_.plan().guide) {
      traced.guide = stages_.guide_on_grid(frame.g, traced.grid, frame.guide);
      frame.guide = GuideFrame();
    }
    if (mode_ == TemporalMode::kEma) {
      if (s.restart) ema_valid_ = false;
      ema_step(parts_.index(s.read), std::move(traced));
      if (s.read == n && s.finish) return frame;
      return std::nullopt;
    }
    WindowFrame lit{std::move(traced), nullptr, nullptr};
    // Kept until the frame is written: its input's headers (the file it was lit from), and its
    // passes unless it is read again to be finished. Motion only served the trace grid, which
    // the ring holds.
    if (still_to_write(s.read, s.output)) lit.input = frame.input;
    if (still_to_write(s.read, s.output) && !read_twice_) {
      frame.g.motion_prev = Image();
      frame.g.motion_next = Image();
      lit.g = std::make_shared<GBuffer>(std::move(frame.g));
    }
    ring_[s.read] = std::move(lit);
    return std::nullopt;
  }

  void ema_step(int index, TracedLight traced) {
    const bool follows = ema_valid_ && ema_index_ == index - 1;
    ema_out_ = follows ? temporal_ema(traced.grid, traced.light, ema_grid_, ema_out_,
                                      stages_.settings().ema_alpha)
                       : std::move(traced.light);
    // The next step reprojects from this frame: its trace grid is all it reads.
    ema_grid_ = std::move(traced.grid);
    ema_coverage_ = std::move(traced.coverage);
    ema_index_ = index;
    ema_valid_ = true;
  }

  // Frame n's light filtered, finished and composited into *m. `own` is frame n as read at this
  // step, if it was.
  void finish(int n, std::optional<InputFrame> own, FinishedFrame* m) {
    if (const auto it = failed_.find(n); it != failed_.end()) rethrow(it->second);
    Image indirect, coverage;
    std::shared_ptr<GBuffer> g;
    if (mode_ == TemporalMode::kWindow) {
      std::vector<const TracedLight*> lit_frames;  // the window's, as lit
      std::vector<const TracedLight*> traced;      // those multiframe reads
      int center = -1, traced_center = -1;
      for (int f : seq_.frames_on_disk) {
        if (!parts_.in_window(f, n, radius_)) continue;
        if (const auto it = failed_.find(f); it != failed_.end()) {
          if (warned_.insert(f).second)
            log_warning((it->second.file.empty() ? seq_.pattern.path_for(f) : it->second.file) +
                        ": " + it->second.what + "; left out of the temporal window");
          continue;
        }
        const auto it = ring_.find(f);
        if (it == ring_.end())
          throw Error(ErrorKind::kInternal, seq_.pattern.path_for(f),
                      "frame " + std::to_string(f) + " of the temporal window was not lit");
        if (f == n) {
          center = static_cast<int>(lit_frames.size());
          traced_center = static_cast<int>(traced.size());
        }
        lit_frames.push_back(&it->second.traced);
        if (std::abs(f - n) <= stages_.plan().multiframe) traced.push_back(&it->second.traced);
      }
      WindowFrame& lit = ring_.at(n);
      if (read_twice_) {
        if (!own)
          throw Error(ErrorKind::kInternal, seq_.pattern.path_for(n),
                      "frame " + std::to_string(n) + " was not read again");
        // Finished from the file it was lit from, or not at all.
        if (lit.input) check_unchanged(*lit.input, *own->input);
        lit.g = std::make_shared<GBuffer>(std::move(own->g));
        lit.input = std::move(own->input);
      }
      // The gi stage's last step for frame n, its rays continued in the window's frames; then
      // the temporal stage over the window's light, with what that continuation changed.
      const std::optional<ContinuedLight> continued =
          stages_.plan().multiframe > 0 ? stages_.continue_in_window(*lit.g, traced, traced_center)
                                        : std::nullopt;
      Image filtered =
          filter_window(lit_frames, center, radius_, continued ? &*continued : nullptr);
      if (stages_.plan().guide) {
        GuideReport report;
        filtered = stages_.guided(*lit.g, lit_frames, center, radius_, filtered, &report);
        m->guide = guide_stats(report);
      }
      indirect = stages_.light_at_frame(*lit.g, filtered);
      coverage = stages_.coverage_at_frame(*lit.g, lit.traced.grid,
                                           continued ? continued->coverage : lit.traced.coverage);
      // The frame's own hits and missed rays served its continuation alone.
      if (lit.traced.trace) lit.traced.trace->release_own();
      // From now on the frame is only a neighbour: reprojection reads its trace grid.
      g = std::move(lit.g);
      m->input = std::move(lit.input);
    } else {
      if (!own)
        throw Error(ErrorKind::kInternal, seq_.pattern.path_for(n),
                    "frame " + std::to_string(n) + " was not read");
      m->input = std::move(own->input);
      const LitViews views =
          mode_ == TemporalMode::kNone ? stages_.light_views(own->views) : LitViews();
      own->views.clear();
      g = std::make_shared<GBuffer>(std::move(own->g));
      if (mode_ == TemporalMode::kEma) {
        indirect = stages_.light_at_frame(*g, ema_out_);
        coverage = stages_.coverage_at_frame(*g, ema_grid_, ema_coverage_);
      } else if (stages_.plan().guide) {
        // The guide's residual is filtered on the trace grid, as the window does.
        TracedLight t = stages_.grid_light(*g, &views);
        t.guide = stages_.guide_on_grid(*g, t.grid, own->guide);
        own->guide = GuideFrame();
        GuideReport report;
        indirect = stages_.light_at_frame(*g, stages_.guided(*g, {&t}, 0, 0, t.light, &report));
        m->guide = guide_stats(report);
        coverage = stages_.coverage_at_frame(*g, t.grid, t.coverage);
      } else {
        indirect = stages_.indirect_light(*g, &coverage, &views);
      }
    }
    // Unless a callback or the preview reads the passes after it, the composite is written over
    // the frame's albedo and beauty: it then takes no plane besides the frame's own.
    const bool passes_read_after = callbacks_.on_result || job_.write_needs_passes;
    m->result = std::make_shared<FrameResult>(
        passes_read_after
            ? stages_.composite(*g, std::move(indirect), std::move(coverage))
            : stages_.composite_in_place(g.get(), std::move(indirect), std::move(coverage)));
    m->g = std::move(g);
    if (seq_.context) cut_to(seq_.data_window, &m->g, m->result.get());
  }

  void write(FinishedFrame m) {
    if (m.output < 0 || stopped_) return;
    FrameReport fr;
    fr.frame = seq_.frames[m.output];
    fr.input = seq_.pattern.path_for(fr.frame);
    fr.output = job_.output_path ? job_.output_path(fr.frame) : "";
    if (m.reused) {
      fr.ok = fr.skipped = true;
    } else {
      fr.read_ms = m.read_ms;
      fr.gi_ms = m.gi_ms;
      try {
        if (m.error) rethrow(*m.error);
        fr.sanitized = m.g->sanitized;
        fr.guide = m.guide;
        if (callbacks_.on_result) caller_.call([&] { callbacks_.on_result(*m.g, *m.result); });
        // The passes go before the frame is encoded unless writing reads them.
        if (!job_.write_needs_passes) m.g = std::make_shared<const GBuffer>(without_planes(*m.g));
        const auto start = Clock::now();
        if (job_.write) job_.write(*m.g, *m.result, *m.input);
        fr.write_ms = ms_since(start);
        fr.ok = true;
      } catch (const Error& e) {
        fr.error_kind = e.kind();
        fr.error_file = e.file();
        fr.error = e.what();
      } catch (const std::bad_alloc&) {
        fr.error_kind = ErrorKind::kIO;
        fr.error_file = fr.input;
        fr.error = "out of memory";
      }
    }
    fr.seconds = (fr.read_ms + fr.gi_ms + fr.write_ms) / 1000.0;
    if (!fr.ok && job_.fail_fast) stopped_ = true;  // the frames after it are not attempted
    const int done = m.output + 1;
    caller_.post([this, fr, done] {
      report_.frames.push_back(fr);
      if (!callbacks_.on_frame || callback_failure_) return;
      try {
        callbacks_.on_frame(report_.frames.back(), done, report_.total);
      } catch (...) {
        callback_failure_ = std::current_exception();
        stopped_ = true;
      }
    });
  }

  // A frame in the window's ring.
  struct WindowFrame {
    // Its trace grid (what reprojection reads), its own light and coverage there before
    // temporal filtering, and with multiframe what continuing rays reads.
    TracedLight traced;
    std::shared_ptr<GBuffer> g;                 // while it is still to be written
    std::shared_ptr<const DecodedInput> input;  // while it is still to be written
  };

  const SequenceJob& job_;
  const SequenceInfo& seq_;
  const FrameStages& stages_;
  const RunCallbacks& callbacks_;
  const TemporalMode mode_;
  const int radius_;
  const bool read_twice_;  // SequenceJob::read_twice, in the window mode
  const ShotParts parts_;
  std::vector<Step> steps_;
  std::map<int, int> output_index_;  // frames to make -> their index in seq_.frames

  // The lighting stage's state.
  std::map<int, WindowFrame> ring_;
  std::map<int, FrameError> failed_;                // frames that could not be read or lit
  std::set<int> warned_;                            // of those, the ones warned about as neighbours
  std::map<int, std::pair<double, double>> times_;  // per frame: read_ms, gi_ms so far
  int ema_index_ = 0;
  bool ema_valid_ = false;
  GBuffer ema_grid_;    // the last frame stepped's trace grid
  Image ema_out_;       // its filtered light on the grid
  Image ema_coverage_;  // its coverage on the grid (not filtered)

  std::atomic<bool> stopped_{false};
  CallerThread caller_;
  // Owned by the calling thread.
  RunReport report_;
  std::exception_ptr callback_failure_;
};

}  // namespace

int frames_waiting(TemporalMode mode, int temporal_radius, bool read_twice) {
  return mode == TemporalMode::kWindow && !read_twice ? temporal_radius : 0;
}

RunReport process_sequence(const SequenceJob& job, const RunCallbacks& callbacks) {
  Processor processor(job, callbacks);
  return processor.run();
}

}  // namespace ssgi::detail

namespace ssgi {

int RunReport::failed() const {
  int n = 0;
  for (const FrameReport& f : frames) n += f.ok ? 0 : 1;
  return n;
}

int RunReport::skipped() const {
  int n = 0;
  for (const FrameReport& f : frames) n += f.skipped ? 1 : 0;
  return n;
}

}  // namespace ssgi
