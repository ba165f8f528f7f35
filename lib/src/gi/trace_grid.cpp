#include "gi/trace_grid.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "gi/surface_model.h"
#include "parallel.h"

namespace ssgi::detail {

TraceGrid make_trace_grid(const GBuffer& g, bool with_emission, int scale, float thickness) {
  TraceGrid grid;
  const int w = g.width(), h = g.height();
  assert(scale >= 1 && scale <= 8);  // a block's depths fit make_trace_grid's array
  grid.scale = scale;
  grid.width = (w + scale - 1) / scale;
  grid.height = (h + scale - 1) / scale;
  const Camera& cam = g.camera;
  const float inv_scale = 1.0f / static_cast<float>(scale);
  grid.fx = static_cast<float>(cam.fx) * inv_scale;
  grid.fy = static_cast<float>(cam.fy) * inv_scale;
  grid.cx = static_cast<float>(cam.cx - (g.data_window.x0 - g.display_window.x0)) * inv_scale;
  grid.cy = static_cast<float>(cam.cy - (g.data_window.y0 - g.display_window.y0)) * inv_scale;
  const std::size_t n = static_cast<std::size_t>(grid.width) * grid.height;
  grid.origin.assign(n, -1);
  grid.depth = Image(grid.width, grid.height, 1, std::numeric_limits<float>::infinity());
  grid.normal = Image(grid.width, grid.height, 3);
  grid.reflected = Image(grid.width, grid.height, 3);
  grid.albedo = Image(grid.width, grid.height, 3);
  const float* depth = g.depth.plane(0);
  // The light a surface reflects towards others, read where a sample needs it rather than kept
  // for the whole frame: direct (albedo included), plus emission. Negative light (a renderer's
  // denoiser can leave some) is not a source.
  const bool emission = with_emission && !g.emission.empty();
  auto reflected = [&](int c, int p) {
    float v = std::max(0.0f, g.direct.plane(c)[p]);
    if (emission) v += std::max(0.0f, g.emission.plane(c)[p]);
    return v;
  };
  parallel_for_rows(grid.height, [&](int by) {
    // A block's finite depths, kept sorted as they come: at most 8 x 8, where insertion costs
    // less than a selection algorithm.
    std::array<float, 64> depths;
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      int finite = 0;
      const int x0 = bx * scale, y0 = by * scale;
      const int x1 = std::min(x0 + scale, w), y1 = std::min(y0 + scale, h);
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const float z = depth[static_cast<std::size_t>(y) * w + x];
          if (!std::isfinite(z)) continue;
          int k = finite++;
          for (; k > 0 && depths[k - 1] > z; --k) depths[k] = depths[k - 1];
          depths[k] = z;
        }
      if (finite == 0) continue;
      // The pixel nearest the median depth; on a tie the nearer one, then the first in
      // scanline order.
      const float median = depths[finite / 2];
      int best = -1;
      float best_d = std::numeric_limits<float>::infinity(), best_z = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const int p = y * w + x;
          const float z = depth[p];
          if (!std::isfinite(z)) continue;
          const float d = std::fabs(z - median);
          if (d < best_d || (d == best_d && z < best_z)) {
            best = p;
            best_d = d;
            best_z = z;
          }
        }
      grid.origin[s] = best;
      const float n[3] = {g.normal.plane(0)[best], g.normal.plane(1)[best],
                          g.normal.plane(2)[best]};
      for (int c = 0; c < 3; ++c) grid.normal.plane(c)[s] = n[c];
      if (scale == 1) {
        grid.depth.plane(0)[s] = best_z;
        for (int c = 0; c < 3; ++c) {
          grid.reflected.plane(c)[s] = reflected(c, best);
          grid.albedo.plane(c)[s] = std::clamp(g.albedo.plane(c)[best], 0.0f, 1.0f);
        }
        continue;
      }
      // The origin's plane at the block's centre: a plane stays a plane on the grid.
      auto ray = [&](float sx, float sy) {
        return std::array<float, 3>{(sx * inv_scale - grid.cx) / grid.fx,
                                    (grid.cy - sy * inv_scale) / grid.fy, 1.0f};
      };
      const std::array<float, 3> ro = ray(best % w + 0.5f, best / w + 0.5f);
      const std::array<float, 3> rc =
          ray(static_cast<float>(x0) + 0.5f * scale, static_cast<float>(y0) + 0.5f * scale);
      const float num = best_z * (n[0] * ro[0] + n[1] * ro[1] + n[2] * ro[2]);
      const float den = n[0] * rc[0] + n[1] * rc[1] + n[2] * rc[2];
      const float zc = num / den;
      grid.depth.plane(0)[s] = den != 0 && zc > 0.5f * best_z && zc < 2.0f * best_z ? zc : best_z;
      // The block's light: its pixels on the origin's surface, averaged.
      float sum[6] = {0, 0, 0, 0, 0, 0};
      int count = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const int p = y * w + x;
          const float z = depth[p];
          if (!(std::fabs(z - best_z) <= thickness * best_z)) continue;
          for (int c = 0; c < 3; ++c) {
            sum[c] += reflected(c, p);
            sum[3 + c] += std::clamp(g.albedo.plane(c)[p], 0.0f, 1.0f);
          }
          ++count;
        }
      for (int c = 0; c < 3; ++c) {
        grid.reflected.plane(c)[s] = sum[c] / static_cast<float>(count);
        grid.albedo.plane(c)[s] = sum[3 + c] / static_cast<float>(count);
      }
    }
  });
  grid.thickness = feature_thickness(grid.depth, grid.normal, grid.fx, grid.fy, grid.cx, grid.cy,
                                     SurfaceModel{thickness});
  return grid;
}

}  // namespace ssgi::detail
