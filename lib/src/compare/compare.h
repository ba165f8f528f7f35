// ssgi's error metrics on planar float images, and their summary over a sequence (the library
// side of `ssgi compare --metric` and of `ssgi sweep`).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ssgi/compare.h"
#include "ssgi/image.h"

namespace ssgi {

// True for PSNR and SSIM, where a larger value is a closer match.
bool metric_higher_is_better(Metric metric);
// relMSE = mean((a - b)^2 / (b^2 + epsilon)): epsilon keeps near-black reference pixels from
// dominating (the value used by Rousselle et al. and most denoising papers).
constexpr double kRelMseEpsilon = 0.01;
// A reference depth at or beyond this (or not finite) marks a background pixel: Blender writes
// 1e10, Arnold AI_BIG (1e12), others inf.
constexpr double kBackgroundDepth = 1e9;

// A group of planes reported together (an EXR layer such as `indirect`).
struct CompareLayer {
  std::string name;
  std::vector<int> planes;  // plane indices, the same in both images
  bool rgb = false;         // planes are R, G, B: SSIM uses their Rec.709 luminance
};

// Compares `a` against the reference `b` (same size and plane count). `background`, when not
// empty, holds one byte per pixel, nonzero for pixels left out of every layer's metrics.
CompareResult compare_images(const Image& a, const Image& b,
                             const std::vector<CompareLayer>& layers, const CompareOptions& options,
                             const std::vector<std::uint8_t>& background = {});

// The background mask of a reference depth plane: 1 where depth is not finite or
// |depth| >= kBackgroundDepth.
std::vector<std::uint8_t> background_from_depth(const float* depth, std::size_t pixels);

// One metric across a sequence.
struct MetricSummary {
  std::optional<double> mean;   // over the frames where it is defined
  std::optional<double> worst;  // largest error (smallest PSNR, SSIM)
  int worst_index = -1;         // the frame that has it, as an index into the results
};

// One layer (by name) across a sequence.
struct LayerSummary {
  std::string name;
  std::array<MetricSummary, kMetricCount> metrics;
};

// A sequence's metrics summed up.
struct SequenceSummary {
  std::vector<LayerSummary> layers;  // in order of first appearance
  LayerSummary overall;
};

// Summarises per-frame results (an empty list gives an empty summary).
SequenceSummary summarize_frames(const std::vector<CompareResult>& frames);

}  // namespace ssgi
