// A guide (--guide): a few-sample render of the shot by its renderer, carrying the renderer's
// diffuse indirect light (the layout role `indirect`), at the shot's resolution or an integer
// fraction of it. Its noise is high but its level is right, which is what screen-space light
// cannot know of what the frame does not show; gi/guide.h combines the two.
#pragma once

#include <memory>
#include <vector>

#include "io/color.h"
#include "io/guide_frame.h"
#include "io/sequence_info.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"

namespace ssgi::detail {

// Opens options.guide against the shot `shot` (opened from `options`): probed from the file of
// the shot's first frame, read with the shot's options (layout, --channel, conventions, camera).
// Throws Error(kInput) naming the file for a guide without indirect light (and without the albedo
// to divide it by, when its layout's light passes include the albedo), without depth, or whose
// display window is not the shot's divided by one integer on both axes (or whose data window is
// not its whole display window); Error(kIO) naming it for a missing or unreadable file.
std::shared_ptr<const GuideInfo> open_guide(const SequenceInfo& shot, const InputOptions& options);

// Throws Error(kIO) naming the first file the guide lacks for one of `frames` (those a run
// reads: the frames it writes and their temporal neighbours), before a run computes anything.
void check_guide_covers(const SequenceInfo& shot, const std::vector<int>& frames);

// Frame `frame` of the shot's guide, checked against `shot_frame` (the shot's frame as read):
// Error(kInput) naming the guide's file for non-finite light and for a depth that does not show
// the shot's surfaces (another camera, or another shot).
GuideFrame read_guide(const SequenceInfo& shot, int frame, const GBuffer& shot_frame,
                      const InputOptions& options, const ColorManagement* color);

}  // namespace ssgi::detail
