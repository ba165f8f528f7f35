// The temporal stage: reprojection of other frames' indirect light, disocclusion rejection,
// variance clipping (Salvi 2016), the seed's exponential moving average and the symmetric window.
#pragma once

#include <vector>

#include "ssgi/gbuffer.h"
#include "ssgi/image.h"

namespace ssgi::detail {

// Carries `history` (3 channels over frames[to]'s data window) into frames[from]: for each
// surface pixel of frames[from], the bilinear lookup of `history` where the same surface point
// is in frames[to], from the taps that pass the disocclusion tests. `frames` are frames of one
// shot in ascending frame order, all with the same windows (the frame loop's ring); the ones
// between `from` and `to` carry motion vectors across several frames. Where no history is
// found (disoccluded, off-screen, background) the result is 0 and `*valid` (if given, 1
// channel) is 0, else `*valid` is 1. Finite everywhere. Throws Error(kInternal) when the
// frames or images disagree in size.
Image reproject(const std::vector<const GBuffer*>& frames, int from, int to, const Image& history,
                Image* valid);

// The same for two frames: motion vectors are used when they are adjacent frames.
Image reproject(const GBuffer& current, const GBuffer& other, const Image& other_history,
                Image* valid);

// Variance clipping (Salvi 2016): where `valid` is 1 on a surface pixel of `current`, moves
// `history` towards the mean of the 3x3 surface neighbourhood of `current_indirect` until it
// lies within mean +- gamma * sigma per channel (sigma with a floor relative to the mean, so
// that the residual noise of already denoised light is not mistaken for change). Elsewhere
// `history` is left as it is.
void clip_history(const GBuffer& current, const Image& current_indirect, const Image& valid,
                  Image* history);

// The symmetric window: the mean of frames[center]'s `indirect` and the clipped reprojections
// of the other frames within `radius` frame numbers of it, each pixel over the frames where
// history was found (equal weights). `frames` and `indirect` (each frame's own light, never a
// filtered result) are the frame loop's ring in ascending frame order; frames outside the
// window are ignored, frames beyond the shot's ends are simply absent. The result depends on
// the window's inputs alone, so a chunk that reads the `radius` frames on disk beyond each of
// its ends gives the same bits as any other chunking, for any thread count. Throws
// Error(kInternal) on mismatched inputs.
Image temporal_window(const std::vector<const GBuffer*>& frames,
                      const std::vector<const Image*>& indirect, int center, int radius);

// How much brighter frame `a` is than frame `b` where they show the same surfaces: over a
// lattice of each frame's surface pixels (about 64 x 64, all of a smaller grid) that the other
// shows too (static points carried through the two cameras, the other frame's sample at the
// point within 2% of the depth predicted), the sum of a's `a_light` over that of b's `b_light`
// at the same points (R + G + B; 3-channel images over each frame's data window). Symmetric: b
// against a is the inverse. NaN when they share fewer than 16 samples or either sum is not
// positive: a cut, or a view that moved on. Throws Error(kInternal) when an image is not its
// frame's size.
double shared_light_ratio(const GBuffer& a, const Image& a_light, const GBuffer& b,
                          const Image& b_light);

// The seed's exponential moving average (Sachdeva 2022): alpha * current + (1 - alpha) *
// history, where history is `previous_output` (this function's result for `previous`, or its
// own light for the first frame of a run) reprojected and clipped; the current light alone
// where no history is found. Throws Error(kUsage) unless 0 < alpha <= 1.
Image temporal_ema(const GBuffer& current, const Image& current_indirect, const GBuffer& previous,
                   const Image& previous_output, float alpha);

// The frames an EMA run must start before the first frame it writes so that its results
// differ from a run over the whole shot by at most `relative_bound` times the largest
// indirect value: the head start's influence decays as (1 - alpha)^frames. Throws
// Error(kUsage) unless 0 < alpha <= 1 and 0 < relative_bound < 1.
int ema_preroll_frames(float alpha, double relative_bound);

}  // namespace ssgi::detail
