// One frame's pipeline: the public face of its stages (frame_stages.h).
#include "ssgi/pipeline.h"

#include <utility>

#include "frame_stages.h"

namespace ssgi {

Pipeline::Pipeline(const SequenceInfo& sequence, const GiSettings& settings)
    : stages_(std::make_unique<detail::FrameStages>(sequence, settings)) {}

Pipeline::~Pipeline() = default;

const Plan& Pipeline::plan() const { return stages_->plan(); }
const GiSettings& Pipeline::settings() const { return stages_->settings(); }
const ColorManagement& Pipeline::color() const { return stages_->color(); }

Image Pipeline::indirect_light(const GBuffer& frame, Image* coverage,
                               const std::vector<GBuffer>* views) const {
  if (!views) return stages_->indirect_light(frame, coverage);
  const detail::LitViews lit = stages_->light_views(*views);
  return stages_->indirect_light(frame, coverage, &lit);
}

std::string Pipeline::describe_misses(const GBuffer& frame) const {
  return stages_->describe_misses(frame);
}

FrameResult Pipeline::composite(const GBuffer& frame, Image indirect, Image coverage) const {
  return stages_->composite(frame, std::move(indirect), std::move(coverage));
}

}  // namespace ssgi
