// Temporal stability of ssgi's indirect light on a Cycles sample sequence: the mean absolute
// frame-to-frame change of `indirect` on static surfaces, relative to its mean, following each
// surface point into the previous frame with the input's motion vectors (Blender's Vector pass:
// pixels, y up, XY = previous - current) and skipping points whose previous depth differs by
// more than 5% (disocclusions). With a still camera (STATIC_CAMERA = 1, `stage`) only pixels
// whose vector is below 0.01 px count, which leaves out the moving ball; with a moving camera
// and a still scene (`room`) every surface counts. The same measure on the truth (DiffInd) is
// printed beside it: the truth changes too, with its path-tracing noise and where the lighting
// changes.
// Usage: temporal_stability IN_PATTERN OUT_PATTERN FIRST LAST STATIC_CAMERA(0|1)
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "exr_planes.h"

namespace {

using accuracy::plane;
using accuracy::Planes;

std::string frame_path(const std::string& pattern, int frame) {
  char digits[16];
  std::snprintf(digits, sizeof digits, "%04d", frame);
  const auto pos = pattern.find("####");
  return pattern.substr(0, pos) + digits + pattern.substr(pos + 4);
}

float bilinear(const std::vector<float>& p, int w, int h, float x, float y) {
  x -= 0.5f;
  y -= 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float tx = x - x0, ty = y - y0;
  auto at = [&](int xi, int yi) {
    xi = std::min(std::max(xi, 0), w - 1);
    yi = std::min(std::max(yi, 0), h - 1);
    return p[static_cast<std::size_t>(yi) * w + xi];
  };
  return (at(x0, y0) * (1 - tx) + at(x0 + 1, y0) * tx) * (1 - ty) +
         (at(x0, y0 + 1) * (1 - tx) + at(x0 + 1, y0 + 1) * tx) * ty;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: temporal_stability IN_PATTERN OUT_PATTERN FIRST LAST STATIC\n");
    return 2;
  }
  const int first = std::atoi(argv[3]), last = std::atoi(argv[4]);
  const bool static_camera = std::atoi(argv[5]) != 0;
  const std::string v = "ViewLayer.";
  const char* rgb[3] = {"R", "G", "B"};
  double ours_change = 0, ours_sum = 0, truth_change = 0, truth_sum = 0;
  std::size_t n = 0;
  int w, h;
  Planes prev_in, prev_out;
  for (int f = first; f <= last; ++f) {
    Planes in = accuracy::read_planes(frame_path(argv[1], f), &w, &h);
    Planes out = accuracy::read_planes(frame_path(argv[2], f), &w, &h);
    if (f > first) {
      const auto& depth = plane(in, v + "Depth.Z");
      const auto& prev_depth = plane(prev_in, v + "Depth.Z");
      const auto& vx = plane(in, v + "Vector.X");
      const auto& vy = plane(in, v + "Vector.Y");
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * w + x;
          if (!(depth[i] < 1e9f)) continue;
          if (static_camera && std::hypot(vx[i], vy[i]) > 0.01f) continue;
          // Blender: XY = previous - current, y up; image y grows down.
          const float px = x + 0.5f + vx[i], py = y + 0.5f - vy[i];
          if (px < 1 || py < 1 || px > w - 1 || py > h - 1) continue;
          const float pd = bilinear(prev_depth, w, h, px, py);
          if (!(pd < 1e9f) || std::fabs(pd - depth[i]) > 0.05f * depth[i]) continue;
          for (int c = 0; c < 3; ++c) {
            const float o = plane(out, std::string("indirect.") + rgb[c])[i];
            const float po =
                bilinear(plane(prev_out, std::string("indirect.") + rgb[c]), w, h, px, py);
            const float t = plane(in, v + "DiffInd." + rgb[c])[i];
            const float pt = bilinear(plane(prev_in, v + "DiffInd." + rgb[c]), w, h, px, py);
            ours_change += std::fabs(o - po);
            ours_sum += o;
            truth_change += std::fabs(t - pt);
            truth_sum += t;
          }
          ++n;
        }
    }
    prev_in = std::move(in);
    prev_out = std::move(out);
  }
  std::printf("%.4f %.4f %zu\n", ours_change / ours_sum, truth_change / truth_sum, n);
  return 0;
}
