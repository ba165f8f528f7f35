// Error of ssgi's output against a path-traced truth that the input carries (Cycles' DiffInd):
// relative RMSE (RMSE / mean of the truth over surface pixels, all channels) of `indirect`
// against DiffInd, and of the composite against (DiffDir + DiffInd) x DiffCol + Emit, plus
// the same for no GI at all, and of the oracle ambient: the truth's own mean DiffInd over the
// surface pixels, per channel, as a constant indirect (the best a constant can do on this
// frame). Surface pixels: Depth.Z < 1e9.
// Usage: truth_error [--second INPUT2.exr] INPUT.exr OUTPUT.exr [LAYER_PREFIX]
// prints: no-GI indirect, indirect, no-GI composite, composite, oracle-ambient indirect, the
// level of ssgi's indirect (its mean over the surface pixels over the truth's: below 1 too
// dark overall, above 1 too bright), and the indirect's error at the truth's level: each
// channel of ssgi's indirect scaled so that its mean over the surface pixels is the truth's.
// That last column is the error of where the light goes, with how much light there is taken
// out: the part of the error no choice of overall level (what the miss model mostly decides)
// could remove.
// With --second INPUT2.exr (the same frame rendered again with another sampling seed), the truth
// is the two renders' mean, and each squared error has the truth's own noise taken out: per
// pixel, (T1 - T2)^2 / 4 estimates the variance of their mean, whose square error it adds in
// expectation, so what is left estimates the error against the noise-free light (a sum that
// noise takes below zero prints 0). An eighth column then says how noisy one render of the
// truth is: the relative RMSE of its noise alone.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "exr_planes.h"

namespace {

using accuracy::plane;
using accuracy::Planes;

}  // namespace

int main(int argc, char** argv) {
  std::string second;
  if (argc > 2 && std::string(argv[1]) == "--second") {
    second = argv[2];
    argc -= 2;
    argv += 2;
  }
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: truth_error [--second INPUT2.exr] INPUT.exr OUTPUT.exr [LAYER_PREFIX]\n");
    return 2;
  }
  const std::string prefix = argc > 3 ? std::string(argv[3]) + "." : "";
  int w, h, w2, h2, w3 = 0, h3 = 0;
  const Planes in = accuracy::read_planes(argv[1], &w, &h);
  const Planes out = accuracy::read_planes(argv[2], &w2, &h2);
  const Planes again = second.empty() ? Planes() : accuracy::read_planes(second, &w3, &h3);
  if (!second.empty() && (w3 != w || h3 != h)) {
    std::fprintf(stderr, "%s: %dx%d, not %dx%d as %s\n", second.c_str(), w3, h3, w, h, argv[1]);
    return 3;
  }
  const std::string v = "ViewLayer.";
  const auto& depth = plane(in, v + "Depth.Z");
  double se_ind = 0, se_comp = 0, se_ind0 = 0, se_comp0 = 0, se_oracle = 0, sum_ind = 0,
         sum_comp = 0, sum_ssgi = 0;
  std::size_t n = 0;
  double se_leveled = 0, noise = 0;
  const char* rgb[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    // The truth: one render's, or the mean of two (with `noise`, its variance per pixel).
    std::vector<float> truth_ind = plane(in, v + "DiffInd." + rgb[c]);
    std::vector<float> variance(truth_ind.size(), 0.0f);
    if (!second.empty()) {
      const auto& other = plane(again, v + "DiffInd." + rgb[c]);
      for (std::size_t i = 0; i < truth_ind.size(); ++i) {
        const float difference = truth_ind[i] - other[i];
        truth_ind[i] = 0.5f * (truth_ind[i] + other[i]);
        variance[i] = 0.25f * difference * difference;
      }
    }
    const auto& dir = plane(in, v + "DiffDir." + rgb[c]);
    const auto& col = plane(in, v + "DiffCol." + rgb[c]);
    const auto& emit = plane(in, v + "Emit." + rgb[c]);
    const auto& ind = plane(out, prefix + "indirect." + rgb[c]);
    const auto& comp = plane(out, prefix + rgb[c]);
    double sum_channel = 0, sum_ours = 0;
    std::size_t n_channel = 0;
    for (std::size_t i = 0; i < depth.size(); ++i) {
      if (!(depth[i] < 1e9f)) continue;
      sum_channel += truth_ind[i];
      sum_ours += ind[i];
      ++n_channel;
    }
    const double oracle = n_channel ? sum_channel / n_channel : 0.0;
    // No light at all cannot be scaled to the truth's level: it keeps its error.
    const double to_level = sum_ours > 0 ? sum_channel / sum_ours : 1.0;
    for (std::size_t i = 0; i < depth.size(); ++i) {
      if (!(depth[i] < 1e9f)) continue;
      const double truth_comp = (dir[i] + truth_ind[i]) * col[i] + emit[i];
      const double none_comp = dir[i] * col[i] + emit[i];
      const double var = variance[i], var_comp = var * col[i] * double(col[i]);
      se_ind += (ind[i] - truth_ind[i]) * double(ind[i] - truth_ind[i]) - var;
      se_ind0 += truth_ind[i] * double(truth_ind[i]) - var;
      se_oracle += (oracle - truth_ind[i]) * (oracle - truth_ind[i]) - var;
      const double leveled = to_level * ind[i] - truth_ind[i];
      se_leveled += leveled * leveled - var;
      se_comp += (comp[i] - truth_comp) * (comp[i] - truth_comp) - var_comp;
      se_comp0 += (none_comp - truth_comp) * (none_comp - truth_comp) - var_comp;
      noise += var;
      sum_ind += truth_ind[i];
      sum_ssgi += ind[i];
      sum_comp += truth_comp;
      ++n;
    }
  }
  const double mean_ind = sum_ind / n, mean_comp = sum_comp / n;
  auto rel = [&](double se, double mean) { return std::sqrt(std::max(se, 0.0) / n) / mean; };
  std::printf("%.4f %.4f %.4f %.4f %.4f %.4f %.4f", rel(se_ind0, mean_ind), rel(se_ind, mean_ind),
              rel(se_comp0, mean_comp), rel(se_comp, mean_comp), rel(se_oracle, mean_ind),
              sum_ssgi / sum_ind, rel(se_leveled, mean_ind));
  // One render's noise: twice the variance of the two renders' mean.
  if (!second.empty()) std::printf(" %.4f", rel(2 * noise, mean_ind));
  std::printf("\n");
  return 0;
}
