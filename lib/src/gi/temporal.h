// The temporal stage: reprojection of other frames' indirect light, disocclusion rejection,
// variance clipping (Salvi 2016), the seed's exponential moving average and the symmetric window.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "gi/guide.h"
#include "ssgi/gbuffer.h"
#include "ssgi/image.h"

namespace ssgi::detail {

struct FrameTrace;

// RGB per group of the miss model's cube faces: sideways, up, down.
using MissColours = std::array<std::array<float, 3>, 3>;

// One frame's light as traced (misses and bounces included) and denoised, at the trace grid's
// resolution, with the grid's geometry as a G-buffer in grid units (depth, normals, motion and
// camera; windows from (0, 0)): what the temporal stage filters.
struct TracedLight {
  GBuffer grid;
  Image light;     // 3 channels, the grid's size
  Image coverage;  // 1 channel, the grid's size: FrameResult::coverage there (-1: no surface)
  // With Plan::multiframe, what continuing its rays and being continued in needs.
  std::shared_ptr<FrameTrace> trace;
  // The window's: the colours the miss model's cube (gi/misses.h) gave the last bounce's misses
  // heading sideways, up and down (RGB each; the sides' four faces weighted by their shares over
  // the frame), and each trace sample's shares of those three, denoised as the light is (3
  // channels; empty when the plan has no window).
  MissColours miss_colours{};
  std::array<float, 3> miss_weight{};  // each group's share of the frame's misses (0: none)
  Image miss_shares;
  Image reflected;    // 3 channels, the grid's size: the light its surfaces reflect
  GuideOnGrid guide;  // Plan::guide: the frame's guide on the grid (FrameStages::guide_on_grid)
};

// The window's lights (TracedLight::light of each of `window`) with the miss model's colours of
// the last bounce levelled over the window: each frame's light plus its shares x (the levelled
// colours - its own), a group's levelled colour being the mean of its colours over the window's
// frames lit alike (those with misses in that group). A frame's border shows other surroundings
// as the view moves; the window's frames together show more, and agree. Two frames are lit
// alike when the surfaces both show reflect the same light, to 1.25x (shared_light_ratio): a
// lamp entering the view changes what a frame shows, a flash changes the light of what both
// show; frames that share no surface are not. Frames without shares are as they are. With
// `changes`, each frame's levelled colours minus its own (0 where it was left as it is): what
// its light moved by per unit of its shares.
std::vector<Image> level_window_misses(const std::vector<const TracedLight*>& window,
                                       std::vector<MissColours>* changes = nullptr);

// A frame's light on its trace grid with its missed rays continued in the window's other
// frames (FrameStages::continue_in_window), denoised as TracedLight::light is.
struct ContinuedLight {
  Image light;        // 3 channels
  Image coverage;     // as TracedLight::coverage, a continued ray that found a surface traced
  Image miss_shares;  // as TracedLight::miss_shares, of the misses left; empty without a window
};

// The temporal stage of the symmetric window for window[center] (the window's frames as lit,
// ascending frame order): each frame's light with the misses' colours levelled over the window
// (level_window_misses), the window's filter over them (temporal_window, `radius`), and with
// `continued`, what continuing the centre's rays changed in its light (add_continued_light).
Image filter_window(const std::vector<const TracedLight*>& window, int center, int radius,
                    const ContinuedLight* continued);

// Adds to `filtered` (the window's result for `own`) what continuing own's missed rays in other
// frames changed in its light: `continued` - own.light, less the levelling the rays that found
// surfaces had had as misses (own.miss_shares - `continued_shares`, times `change`, its
// levelled colours minus its own); never below 0. The window filters each frame's own light,
// so that the continuation is added after.
void add_continued_light(const TracedLight& own, const Image& continued,
                         const Image& continued_shares, const MissColours& change, Image* filtered);

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

// The same for several histories at once (1 to 3, each 3 channels over frames[to]'s data
// window), the disocclusion tests made once for all: each history as the one-history form gives
// it, except that `*valid` and where a pixel is written follow the first alone (a pixel where
// the first is found but another has no finite tap holds 0 in that one).
std::vector<Image> reproject(const std::vector<const GBuffer*>& frames, int from, int to,
                             const std::vector<const Image*>& histories, Image* valid);

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
