// Error of ssgi's output against a path-traced truth that the input carries (Cycles' DiffInd):
// relative RMSE (RMSE / mean of the truth over surface pixels, all channels) of `indirect`
// against DiffInd, and of the composite against (DiffDir + DiffInd) x DiffCol + Emit, plus
// the same for no GI at all, and of the oracle ambient: the truth's own mean DiffInd over the
// surface pixels, per channel, as a constant indirect (the best a constant can do on this
// frame). Surface pixels: Depth.Z < 1e9. Usage: truth_error INPUT.exr OUTPUT.exr [LAYER_PREFIX]
// prints: no-GI indirect, indirect, no-GI composite, composite, oracle-ambient indirect, the
// level of ssgi's indirect (its mean over the surface pixels over the truth's: below 1 too
// dark overall, above 1 too bright), and the indirect's error at the truth's level: each
// channel of ssgi's indirect scaled so that its mean over the surface pixels is the truth's.
// That last column is the error of where the light goes, with how much light there is taken
// out: the part of the error no choice of overall level (what the miss model mostly decides)
// could remove.
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
  if (argc < 3) {
    std::fprintf(stderr, "usage: truth_error INPUT.exr OUTPUT.exr [LAYER_PREFIX]\n");
    return 2;
  }
  const std::string prefix = argc > 3 ? std::string(argv[3]) + "." : "";
  int w, h, w2, h2;
  const Planes in = accuracy::read_planes(argv[1], &w, &h);
  const Planes out = accuracy::read_planes(argv[2], &w2, &h2);
  const std::string v = "ViewLayer.";
  const auto& depth = plane(in, v + "Depth.Z");
  double se_ind = 0, se_comp = 0, se_ind0 = 0, se_comp0 = 0, se_oracle = 0, sum_ind = 0,
         sum_comp = 0, sum_ssgi = 0;
  std::size_t n = 0;
  double se_leveled = 0;
  const char* rgb[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    const auto& truth_ind = plane(in, v + "DiffInd." + rgb[c]);
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
      se_ind += (ind[i] - truth_ind[i]) * double(ind[i] - truth_ind[i]);
      se_ind0 += truth_ind[i] * double(truth_ind[i]);
      se_oracle += (oracle - truth_ind[i]) * (oracle - truth_ind[i]);
      const double leveled = to_level * ind[i] - truth_ind[i];
      se_leveled += leveled * leveled;
      se_comp += (comp[i] - truth_comp) * (comp[i] - truth_comp);
      se_comp0 += (none_comp - truth_comp) * (none_comp - truth_comp);
      sum_ind += truth_ind[i];
      sum_ssgi += ind[i];
      sum_comp += truth_comp;
      ++n;
    }
  }
  const double mean_ind = sum_ind / n, mean_comp = sum_comp / n;
  std::printf("%.4f %.4f %.4f %.4f %.4f %.4f %.4f\n", std::sqrt(se_ind0 / n) / mean_ind,
              std::sqrt(se_ind / n) / mean_ind, std::sqrt(se_comp0 / n) / mean_comp,
              std::sqrt(se_comp / n) / mean_comp, std::sqrt(se_oracle / n) / mean_ind,
              sum_ssgi / sum_ind, std::sqrt(se_leveled / n) / mean_ind);
  return 0;
}
