// Two outputs compared, built against an installed ssgi: the regression check a pipeline runs on
// a frame ssgi wrote against the one it keeps as a reference. Every layer with R, G, B in both
// files (ssgi's indirect and gi, the composite) is compared with ssgi's metrics on the surface
// pixels; exits 0 when each layer's RMSE is at most MAX_RMSE, 1 when one is over it or has no
// pixel to compare, 2 when the files cannot be compared.
#include <cstdio>
#include <cstdlib>

#include "ssgi/compare.h"
#include "ssgi/error.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: compare_outputs OUTPUT REFERENCE MAX_RMSE\n");
    return 2;
  }
  const double max_rmse = std::atof(argv[3]);
  ssgi::FileCompareOptions options;
  options.compare.compute_ssim = false;  // RMSE and PSNR only
  try {
    const ssgi::FileCompareResult r = ssgi::compare_files(argv[1], argv[2], options);
    bool pass = !r.result.layers.empty();
    for (const ssgi::LayerStats& layer : r.result.layers) {
      const auto& rmse = layer.metric(ssgi::Metric::kRmse);
      const auto& psnr = layer.metric(ssgi::Metric::kPsnr);
      std::printf("%-10s rmse %.6g psnr %.2f dB\n",
                  layer.name.empty() ? "(root)" : layer.name.c_str(), rmse ? *rmse : -1.0,
                  psnr ? *psnr : 0.0);
      pass = pass && rmse && *rmse <= max_rmse;
    }
    std::printf("%s\n", pass ? "pass" : "fail");
    return pass ? 0 : 1;
  } catch (const ssgi::Error& e) {
    std::fprintf(stderr, "%s: %s\n", e.file().c_str(), e.what());
    return 2;
  }
}
