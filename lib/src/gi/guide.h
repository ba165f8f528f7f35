// A guide's light with ssgi's as its control variate (--guide, io/guide.h). A few-sample render
// of the renderer's indirect light knows its level but is noise pixel by pixel; ssgi's light is
// smooth but misses what the frame does not show. Their difference, the residual, is what ssgi
// got wrong plus the guide's noise: averaged over the window's frames (reprojected as the light
// is) and fitted over the surface (a constant plus slopes along the normal and log depth, over
// the neighbourhood the denoiser's pyramid averages), it corrects ssgi's level and shapes, and
// where the residual stands out of the fit by more than the guide's own noise it is kept as it
// is, so that a guide without noise gives its own light back.
#pragma once

#include <vector>

#include "io/guide.h"
#include "ssgi/gbuffer.h"
#include "ssgi/image.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// A guide frame on a trace grid, per trace sample and channel (3 channels each).
struct GuideOnGrid {
  Image mean;      // the guide's light over the sample's block on its surface
  Image variance;  // the variance of that mean: the guide's noise over its pixels there
  Image known;     // 1 where the guide gives the light, else 0 (mean and variance are 0 there)
  bool empty() const { return mean.empty(); }
};

// `guide` (frame `frame`'s, at 1 / guide.fraction of its resolution) on the trace grid `grid`
// (TracedLight::grid: trace samples of `scale` x `scale` blocks of the frame's data window).
// A guide pixel gives channel c where it shows a surface whose frame pixel at its centre has
// albedo (an emitter's diffuse light says nothing) and the guide knows c; it is on a sample's
// surface when its depth is within `thickness` x the sample's of it. Each sample's mean is over
// its block's guide pixels on its surface (over the block grown by a guide pixel each side where
// none is); the variance of that mean is the guide's noise, from the second differences along x
// and y of the pixels on the surface in the grown block (where both neighbours give c on the
// pixel's own surface), over the number averaged (0 on a surface without such pixels, too small
// to show noise). A sample without a surface, or without a guide pixel on it in the grown block,
// is not known.
GuideOnGrid guide_on_grid(const GBuffer& frame, const GBuffer& grid, int scale,
                          const GuideFrame& guide, float thickness);

// What the guide did to a frame's light, for -v and --stats.
struct GuideReport {
  // The residual's mean over the guided light's (all channels, the grid's surface samples): the
  // share of the light the guide brought (negative where it took light away).
  double residual_share = 0;
  // The mean weight given to the residual's own detail (0: filtered wholly, 1: as it is).
  double detail_kept = 0;
  // The share of the grid's surface samples the guide gives the light of.
  double known_share = 0;
};

// `light` (3 channels on the grid's trace samples: a frame's light after the temporal stage)
// guided by `guide` (its window's frames' means, variances and known, averaged over the window
// by the caller: the variance divided by the frames averaged): light + the residual guide -
// light, fitted per sample by weighted least squares to a constant plus slopes along the
// normal and the log depth, with a ridge on the slopes that grows with the guide's relative
// noise, over the samples the pyramid of `settings` averages into it (over the grid's
// `grid_depth`, +inf where a sample has no surface, and `grid_normal`, from the grid's pyramid
// level `level` as deep as denoise_on_grid filters the light, but with looser edges), on the
// samples where the guide knows the channel;
// where what the fit leaves has a local energy within the guide's noise it is dropped, where it
// stands out of it kept (a Wiener weight per sample: max(0, energy - noise) / energy, energy and
// noise averaged over the surface as the residual is). Never below 0. Throws Error(kInternal)
// when the images disagree in size.
Image guided_light(const Image& light, const GuideOnGrid& guide, const Image& grid_depth,
                   const Image& grid_normal, int level, const DenoiseSettings& settings,
                   GuideReport* report = nullptr);

}  // namespace ssgi::detail
