// One frame lit from buffers a program made, built against an installed ssgi: a floor under a
// lit wall, the floor in the dark. The floor's only light is what the wall reflects onto it,
// so its indirect light must be above zero (a tracer that misses the wall fails) and, with one
// bounce, at most the light the wall reflects (1).
#include <cmath>
#include <cstdio>

#include "ssgi/error.h"
#include "ssgi/gbuffer.h"
#include "ssgi/pipeline.h"
#include "ssgi/settings.h"

int main() {
  constexpr int kWidth = 96, kHeight = 64;
  constexpr double kFloorY = -1, kWallZ = 4;  // camera space: x right, y up, +z forward
  ssgi::GBuffer g;
  g.frame = 1;
  g.display_window = g.data_window = {0, 0, kWidth, kHeight};
  g.camera = ssgi::camera_from_fov(60, g.display_window);
  g.depth = ssgi::Image(kWidth, kHeight, 1);
  g.normal = ssgi::Image(kWidth, kHeight, 3);
  g.albedo = ssgi::Image(kWidth, kHeight, 3, 0.5f);
  g.direct = ssgi::Image(kWidth, kHeight, 3);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const Imath::V3d d = g.camera.view_dir(x + 0.5, y + 0.5);
      const double to_wall = kWallZ / d.z;
      const double to_floor = d.y < 0 ? kFloorY / d.y : to_wall;
      const bool floor = to_floor < to_wall;
      g.depth.at(0, x, y) = static_cast<float>((floor ? to_floor : to_wall) * d.z);
      g.normal.at(floor ? 1 : 2, x, y) = floor ? 1.0f : -1.0f;  // floor +y, wall facing us
      for (int c = 0; c < 3; ++c) g.direct.at(c, x, y) = floor ? 0.0f : 1.0f;
    }
  }

  ssgi::GiSettings settings;
  ssgi::apply_preset("draft", &settings);
  settings.miss = ssgi::MissMode::kEnvironment;  // a black environment: only the wall lights
  settings.bounces = 1;
  try {
    const ssgi::Pipeline pipeline(*ssgi::still_sequence(g), settings);
    const ssgi::FrameResult result = pipeline.composite(g, pipeline.indirect_light(g));
    double floor_sum = 0;
    int floor_pixels = 0;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        for (int c = 0; c < 3; ++c) {
          if (!std::isfinite(result.indirect.at(c, x, y)) ||
              !std::isfinite(result.composite.at(c, x, y))) {
            std::fprintf(stderr, "not finite at (%d, %d)\n", x, y);
            return 1;
          }
        }
        if (g.normal.at(1, x, y) > 0) {
          floor_sum += result.indirect.at(0, x, y);
          ++floor_pixels;
        }
      }
    }
    const double floor_mean = floor_sum / floor_pixels;
    std::printf("floor: %d pixels, mean indirect light %.4f\n", floor_pixels, floor_mean);
    return floor_pixels > 0 && floor_mean > 0.01 && floor_mean <= 1.0 ? 0 : 1;
  } catch (const ssgi::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
