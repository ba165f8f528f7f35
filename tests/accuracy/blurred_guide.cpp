// What a user could do instead of ssgi: a few-sample render's diffuse indirect light blurred.
// Writes OUTPUT.exr with the layers truth_error reads of ssgi's output: `indirect` (the guide's
// DiffInd, at the shot's resolution, blurred by three passes of a box of RADIUS pixels, default
// 4, over the shot's surface pixels alone: each pass the mean of the surface pixels in the box)
// and the composite R, G, B made with it, (DiffDir + indirect) x DiffCol + Emit. A guide at a
// fraction of the shot's resolution is read pixel for pixel at each shot pixel's centre first.
// Usage: blurred_guide SHOT.exr GUIDE.exr OUTPUT.exr [RADIUS]
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "exr_planes.h"

namespace {

using accuracy::plane;
using accuracy::Planes;

// One pass of a box of `radius` over `value` where `surface` is set: each surface pixel the
// mean of the surface pixels in the (2 radius + 1)^2 box around it (their sums and counts along
// x, then those summed along y).
void box_pass(std::vector<float>* value, const std::vector<char>& surface, int w, int h,
              int radius) {
  std::vector<double> sum(static_cast<std::size_t>(w) * h), count(sum.size());
  std::vector<float> out(*value);
  const auto run = [&](bool along_x) {
    const int lines = along_x ? h : w, length = along_x ? w : h;
    for (int l = 0; l < lines; ++l) {
      const auto at = [&](int i) {
        return along_x ? static_cast<std::size_t>(l) * w + i : static_cast<std::size_t>(i) * w + l;
      };
      for (int i = 0; i < length; ++i) {
        double s = 0, n = 0;
        for (int k = std::max(0, i - radius); k <= std::min(length - 1, i + radius); ++k) {
          if (along_x) {
            if (!surface[at(k)]) continue;
            s += (*value)[at(k)];
            n += 1;
          } else {
            s += sum[at(k)];
            n += count[at(k)];
          }
        }
        if (along_x) {
          sum[at(i)] = s;
          count[at(i)] = n;
        } else if (surface[at(i)] && n > 0) {
          out[at(i)] = static_cast<float>(s / n);
        }
      }
    }
  };
  run(true);
  run(false);
  *value = std::move(out);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: blurred_guide SHOT.exr GUIDE.exr OUTPUT.exr [RADIUS]\n");
    return 2;
  }
  const int radius = argc > 4 ? std::atoi(argv[4]) : 4;
  int w, h, gw, gh;
  const Planes shot = accuracy::read_planes(argv[1], &w, &h);
  const Planes guide = accuracy::read_planes(argv[2], &gw, &gh);
  if (gw <= 0 || w % gw != 0 || w / gw * gh != h) {
    std::fprintf(stderr, "%s: %dx%d is not %dx%d divided by a whole number\n", argv[2], gw, gh, w,
                 h);
    return 3;
  }
  const int f = w / gw;
  const std::string v = "ViewLayer.";
  const std::vector<float>& depth = plane(shot, v + "Depth.Z");
  std::vector<char> surface(depth.size());
  for (std::size_t i = 0; i < depth.size(); ++i) surface[i] = depth[i] < 1e9f;
  const char* rgb[3] = {"R", "G", "B"};
  std::vector<std::string> names;
  std::vector<std::vector<float>> planes;
  for (int c = 0; c < 3; ++c) {
    const std::vector<float>& g = plane(guide, v + "DiffInd." + rgb[c]);
    std::vector<float> ind(depth.size(), 0.0f);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        ind[static_cast<std::size_t>(y) * w + x] = g[static_cast<std::size_t>(y / f) * gw + x / f];
    for (int pass = 0; pass < 3; ++pass) box_pass(&ind, surface, w, h, radius);
    for (std::size_t i = 0; i < ind.size(); ++i)
      if (!surface[i]) ind[i] = 0;
    const std::vector<float>& dir = plane(shot, v + "DiffDir." + rgb[c]);
    const std::vector<float>& col = plane(shot, v + "DiffCol." + rgb[c]);
    const std::vector<float>& emit = plane(shot, v + "Emit." + rgb[c]);
    std::vector<float> comp(ind.size());
    for (std::size_t i = 0; i < ind.size(); ++i) comp[i] = (dir[i] + ind[i]) * col[i] + emit[i];
    names.push_back(std::string("indirect.") + rgb[c]);
    planes.push_back(std::move(ind));
    names.push_back(rgb[c]);
    planes.push_back(std::move(comp));
  }
  OIIO::ImageSpec spec(w, h, static_cast<int>(names.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames = names;
  std::vector<float> interleaved(static_cast<std::size_t>(w) * h * names.size());
  for (std::size_t c = 0; c < names.size(); ++c)
    for (std::size_t i = 0; i < planes[c].size(); ++i)
      interleaved[i * names.size() + c] = planes[c][i];
  auto out = OIIO::ImageOutput::create(argv[3]);
  if (!out || !out->open(argv[3], spec) ||
      !out->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()) || !out->close()) {
    std::fprintf(stderr, "%s: cannot write\n", argv[3]);
    return 4;
  }
  return 0;
}
