// The denoise stage: the seed's depth- and normal-aware bilateral pyramid (Sachdeva 2022).
#pragma once

#include "ssgi/image.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// Throws Error(kUsage) naming the first setting out of range.
void validate_denoise_settings(const DenoiseSettings& settings);

// Denoises the indirect light `noisy` (3 channels) guided by `depth` (1 channel, planar camera
// z, +inf where there is no surface) and `normal` (3 channels, unit camera-space normals):
// downsample `settings.levels` times with the guides, joint bilateral filter at the coarsest
// level, then joint bilateral upsampling with an edge-aware blur back up to full resolution.
// Returns 3 channels of the same size: finite everywhere, 0 on background pixels, and each
// surface pixel a convex combination of surface inputs (non-finite inputs count as 0). The
// result is the same for any thread count. Throws ssgi::Error (kUsage) on invalid settings and
// (kInternal) when the images disagree in size or channel count.
Image denoise_pyramid(const Image& noisy, const Image& depth, const Image& normal,
                      const DenoiseSettings& settings);

// The same pyramid for light traced at a coarser level: `light` is the size of pyramid level
// `light_level` (the data window halved that many times, rounding up; see gather.h's trace
// grid), and is carried up to level `output_level` (<= light_level; 0 is full resolution) by
// joint bilateral upsampling, filtered on the way when `denoise` is set (as denoise_pyramid),
// else only upsampled. The pipeline denoises at the grid's level, filters over time there, and
// upsamples to full resolution last.
Image upsample_and_denoise(const Image& light, int light_level, const Image& depth,
                           const Image& normal, const DenoiseSettings& settings, bool denoise,
                           int output_level = 0);

}  // namespace ssgi::detail
