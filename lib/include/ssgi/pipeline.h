// One frame's pipeline: directions, tracing with its misses and bounces, denoising and the
// composite, under the plan a run decided.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "ssgi/gbuffer.h"
#include "ssgi/plan.h"
#include "ssgi/settings.h"

namespace ssgi {

namespace detail {
class FrameStages;
}

class Pipeline {
 public:
  // Loads what the whole run shares (the colour config and its processors, the environment
  // map). Throws ssgi::Error.
  Pipeline(const SequenceInfo& sequence, const GiSettings& settings);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  const Plan& plan() const;
  const GiSettings& settings() const;
  // The run's colour spaces: the inputs are read into them, and the outputs go through them.
  const ColorManagement& color() const;

  // The frame's indirect light (3 channels) without temporal filtering; with `coverage`, its
  // coverage at the frame's resolution too (FrameResult::coverage). With `views` (the frame's
  // views of the sequence's --view options, each numbered with the frame's number, which seeds
  // its noise), its missed rays continue in them when the plan says so (man ssgi-gi, VIEWS).
  Image indirect_light(const GBuffer& frame, Image* coverage = nullptr,
                       const std::vector<GBuffer>* views = nullptr) const;

  // What the miss model decides for `frame` (man ssgi-gi, MISSES) and the numbers it decides
  // from, in one line: what -v prints per frame.
  std::string describe_misses(const GBuffer& frame) const;

  // The composite stage: outputs from the (temporally filtered) indirect light, and its
  // coverage at the frame's resolution when given (FrameResult::coverage).
  FrameResult composite(const GBuffer& frame, Image indirect, Image coverage = {}) const;

 private:
  std::unique_ptr<const detail::FrameStages> stages_;
};

}  // namespace ssgi
