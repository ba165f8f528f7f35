#include "gather.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "misses.h"
#include "parallel.h"

namespace ssgi::detail {

TraceGrid make_trace_grid(const GBuffer& g, int scale) {
  TraceGrid grid;
  const int w = g.width(), h = g.height();
  grid.scale = scale;
  grid.width = (w + scale - 1) / scale;
  grid.height = (h + scale - 1) / scale;
  grid.full_width = w;
  grid.origin.assign(static_cast<std::size_t>(grid.width) * grid.height, -1);
  const float* depth = g.depth.plane(0);
  parallel_for_rows(grid.height, [&](int by) {
    std::vector<float> depths;
    for (int bx = 0; bx < grid.width; ++bx) {
      depths.clear();
      const int x0 = bx * scale, y0 = by * scale;
      const int x1 = std::min(x0 + scale, w), y1 = std::min(y0 + scale, h);
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const float z = depth[static_cast<std::size_t>(y) * w + x];
          if (std::isfinite(z)) depths.push_back(z);
        }
      if (depths.empty()) continue;
      // The pixel nearest the median depth; on a tie the nearer one, then the first in
      // scanline order.
      std::vector<float> sorted = depths;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      const float median = sorted[sorted.size() / 2];
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
      grid.origin[static_cast<std::size_t>(by) * grid.width + bx] = best;
    }
  });
  return grid;
}

WeightedHits weighted_from_rays(const TraceGrid& grid, const RayHits& rays) {
  WeightedHits hits;
  const std::size_t n = grid.origin.size();
  const int w = grid.width, h = grid.height;
  hits.miss = Image(w, h, 1);
  hits.env = Image(w, h, 3);
  hits.begin.resize(n + 1);
  const float inv = 1.0f / static_cast<float>(rays.rays);
  for (std::size_t s = 0; s < n; ++s) {
    hits.begin[s] = static_cast<std::uint32_t>(hits.pixel.size());
    if (grid.origin[s] < 0) continue;
    const std::size_t p = static_cast<std::size_t>(grid.origin[s]);
    for (int k = 0; k < rays.rays; ++k) {
      const std::int32_t hit = rays.hit[p * rays.rays + k];
      if (hit < 0) continue;
      hits.pixel.push_back(hit);
      hits.weight.push_back(inv);
    }
    hits.miss.plane(0)[s] = rays.miss_count.plane(0)[p] * inv;
    for (int c = 0; c < 3; ++c) hits.env.plane(c)[s] = rays.env_sum.plane(c)[p] * inv;
  }
  hits.begin[n] = static_cast<std::uint32_t>(hits.pixel.size());
  return hits;
}

namespace {

// One gather: the light `radiance(pixel)` of every hit, plus the miss light.
template <typename Radiance>
Image gather_once(const TraceGrid& grid, const WeightedHits& hits, const Radiance& radiance,
                  const MissLight& miss) {
  Image out(grid.width, grid.height, 3);
  parallel_for_rows(grid.height, [&](int by) {
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      if (grid.origin[s] < 0) continue;
      const float m = hits.miss.plane(0)[s];
      std::array<float, 3> sum;
      for (int c = 0; c < 3; ++c)
        sum[c] = miss.env_weight * hits.env.plane(c)[s] + m * miss.frame_radiance[c];
      for (std::uint32_t e = hits.begin[s]; e < hits.begin[s + 1]; ++e) {
        const std::array<float, 3> l = radiance(hits.pixel[e]);
        for (int c = 0; c < 3; ++c) sum[c] += hits.weight[e] * l[c];
      }
      for (int c = 0; c < 3; ++c) out.plane(c)[s] = sum[c];
    }
  });
  return out;
}

// The mean of `radiance` over the grid's origins, for the frame estimate of misses.
template <typename Radiance>
MissLight miss_light_over_grid(const TraceGrid& grid, const Radiance& radiance, double closure) {
  MissLight miss;
  miss.env_weight = static_cast<float>(1.0 - closure);
  if (closure <= 0) return miss;
  // Sums in double, in a fixed order: the same bits for any thread count.
  double sum[3] = {0, 0, 0};
  std::size_t n = 0;
  for (const std::int32_t p : grid.origin) {
    if (p < 0) continue;
    const std::array<float, 3> l = radiance(p);
    for (int c = 0; c < 3; ++c) sum[c] += l[c];
    ++n;
  }
  for (int c = 0; c < 3; ++c)
    miss.frame_radiance[c] = n ? static_cast<float>(closure * sum[c] / n) : 0.0f;
  return miss;
}

}  // namespace

Image gather_bounces(const GBuffer& g, const TraceGrid& grid, const WeightedHits& hits,
                     const Image& reflected, int bounces, double closure) {
  const float* rr = reflected.plane(0);
  const float* rg = reflected.plane(1);
  const float* rb = reflected.plane(2);
  auto first = [&](int p) { return std::array<float, 3>{rr[p], rg[p], rb[p]}; };
  Image indirect = gather_once(grid, hits, first, miss_light_over_grid(grid, first, closure));
  for (int b = 1; b < bounces; ++b) {
    const Image previous = std::move(indirect);
    // Albedo above 1 would add energy at every bounce.
    auto lit = [&](int p) {
      const std::size_t s = static_cast<std::size_t>(grid.block_of(p));
      std::array<float, 3> l = first(p);
      for (int c = 0; c < 3; ++c)
        l[c] += std::clamp(g.albedo.plane(c)[p], 0.0f, 1.0f) * previous.plane(c)[s];
      return l;
    };
    indirect = gather_once(grid, hits, lit, miss_light_over_grid(grid, lit, closure));
  }
  return indirect;
}

}  // namespace ssgi::detail
