#include "gi/gather.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include "gi/misses.h"
#include "gi/surface_model.h"
#include "parallel.h"

namespace ssgi::detail {

WeightedHits weighted_from_rays(const TraceGrid& grid, const RayHits& rays) {
  WeightedHits hits;
  const std::size_t n = grid.origin.size();
  const int w = grid.width, h = grid.height;
  hits.miss = Image(w, h, 1);
  hits.env = Image(w, h, 3);
  hits.cube = Image(w, h, kCubeFaces);
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
    for (int f = 0; f < kCubeFaces; ++f) hits.cube.plane(f)[s] = rays.cube_sum.plane(f)[p] * inv;
  }
  hits.begin[n] = static_cast<std::uint32_t>(hits.pixel.size());
  return hits;
}

namespace {

// WeightedHits' entries as a HitSource, with its own shares or others.
class HeldHits final : public HitSource {
 public:
  HeldHits(const TraceGrid& grid, const WeightedHits& hits, const Image& miss, const Image& env,
           const Image& cube, const Image& continued_light)
      : width_(grid.width),
        hits_(hits),
        miss_(miss),
        env_(env),
        cube_(cube),
        continued_(continued_light) {}
  HitRow row(int by, HitScratch*) const override { return hits_.row(by, width_); }
  const Image& miss() const override { return miss_; }
  const Image& env() const override { return env_; }
  const Image& cube() const override { return cube_; }
  const Image* continued_light() const override {
    return continued_.empty() ? nullptr : &continued_;
  }

 private:
  int width_;
  const WeightedHits& hits_;
  const Image &miss_, &env_, &cube_, &continued_;
};

// One gather: the light `radiance(hit)` of every hit, plus the misses' environment light and
// their cube shares x the cube's colours; with `coverage`, the hits' share of it there
// (gather_bounces).
// Written into `out` (3 channels of the grid's size) where the grid has an origin; the rest of
// it is left as it is.
template <typename Radiance>
void gather_once(const TraceGrid& grid, const HitSource& hits, const Radiance& radiance,
                 const CubeLight& cube, Image* out, Image* coverage = nullptr) {
  if (coverage) *coverage = Image(grid.width, grid.height, 1, -1.0f);
  parallel_for_rows(grid.height, [&](int by) {
    HitScratch scratch;
    const HitRow row = hits.row(by, &scratch);
    const Image& env = hits.env();
    const Image& shares = hits.cube();
    const Image* continued = hits.continued_light();
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      if (grid.origin[s] < 0) continue;
      std::array<float, 3> sum;
      for (int c = 0; c < 3; ++c) sum[c] = env.plane(c)[s];
      for (int f = 0; f < kCubeFaces; ++f) {
        const float share = shares.plane(f)[s];
        for (int c = 0; c < 3; ++c) sum[c] += share * cube[f][c];
      }
      const std::array<float, 3> missed = sum;
      // The hits' light apart too, for the coverage (not sum - missed, which rounding could
      // take below 0 or above the total).
      float from_hits = 0;
      if (continued)
        for (int c = 0; c < 3; ++c) {
          sum[c] += continued->plane(c)[s];
          from_hits += continued->plane(c)[s];
        }
      const std::uint32_t first = row.begin[bx], end = row.begin[bx + 1];
      // Two loops rather than one with the coverage's sum under a flag (a template flag and
      // if constexpr), which ran the bounces slower (BM_Bounces, tests/bench_stages.cpp).
      if (coverage) {
        for (std::uint32_t e = first; e < end; ++e) {
          const std::array<float, 3> l = radiance(row.pixel[e]);
          const float weight = row.weight ? row.weight[e] : row.uniform_weight;
          for (int c = 0; c < 3; ++c) sum[c] += weight * l[c];
          from_hits += weight * (l[0] + l[1] + l[2]);
        }
      } else {
        for (std::uint32_t e = first; e < end; ++e) {
          const std::array<float, 3> l = radiance(row.pixel[e]);
          const float weight = row.weight ? row.weight[e] : row.uniform_weight;
          for (int c = 0; c < 3; ++c) sum[c] += weight * l[c];
        }
      }
      for (int c = 0; c < 3; ++c) out->plane(c)[s] = sum[c];
      if (coverage) {
        const float total = from_hits + (missed[0] + missed[1] + missed[2]);
        coverage->plane(0)[s] = total > 0 && std::isfinite(total)
                                    ? std::clamp(from_hits / total, 0.0f, 1.0f)
                                    : std::clamp(1.0f - hits.miss().plane(0)[s], 0.0f, 1.0f);
      }
    }
  });
}

}  // namespace

Image gather_bounces(const TraceGrid& grid, const WeightedHits& hits, int bounces,
                     const MissModel& misses, Image* coverage, CubeLight* last_cube) {
  return gather_bounces(grid,
                        HeldHits(grid, hits, hits.miss, hits.env, hits.cube, hits.continued_light),
                        bounces, misses, coverage, last_cube);
}

Image gather_bounces(const TraceGrid& grid, const WeightedHits& hits, const MissShares& shares,
                     int bounces, const MissModel& misses, Image* coverage) {
  return gather_bounces(
      grid, HeldHits(grid, hits, shares.miss, shares.env, shares.cube, shares.continued_light),
      bounces, misses, coverage);
}

MissShares take_shares(WeightedHits* hits) {
  return {std::move(hits->miss), std::move(hits->env), std::move(hits->cube),
          std::move(hits->continued_light)};
}

void put_shares(MissShares shares, WeightedHits* hits) {
  hits->miss = std::move(shares.miss);
  hits->env = std::move(shares.env);
  hits->cube = std::move(shares.cube);
  hits->continued_light = std::move(shares.continued_light);
}

Image coverage_to_frame(const Image& grid_coverage, const Image& grid_depth,
                        const Image& grid_normal, int scale, float thickness, const Image& depth) {
  const int gw = grid_coverage.width(), gh = grid_coverage.height();
  const int w = depth.width(), h = depth.height();
  const float* in = grid_coverage.plane(0);
  const float* gz = grid_depth.plane(0);
  const float *gnx = grid_normal.plane(0), *gny = grid_normal.plane(1), *gnz = grid_normal.plane(2);
  auto near = [&](float a, float b) { return std::fabs(a - b) <= thickness * std::min(a, b); };
  // Per sample with a surface, which of its 3 x 3 neighbours (bit 3 (dy + 1) + dx + 1) have one
  // on its surface: their normals agree and their depths are within the slab.
  std::vector<std::uint16_t> same(grid_coverage.plane_size(), 0);
  Image smooth(gw, gh, 1, -1.0f);
  parallel_for_rows(gh, [&](int y) {
    for (int x = 0; x < gw; ++x) {
      const std::size_t s = static_cast<std::size_t>(y) * gw + x;
      if (!(in[s] >= 0)) continue;
      float sum = 0;
      int n = 0;
      std::uint16_t bits = 0;
      for (int qy = std::max(0, y - 1); qy <= std::min(gh - 1, y + 1); ++qy)
        for (int qx = std::max(0, x - 1); qx <= std::min(gw - 1, x + 1); ++qx) {
          const std::size_t q = static_cast<std::size_t>(qy) * gw + qx;
          const float facing = gnx[s] * gnx[q] + gny[s] * gny[q] + gnz[s] * gnz[q];
          if (!(in[q] >= 0) || !(facing > 0.9f) || !near(gz[s], gz[q])) continue;
          sum += in[q], ++n;
          bits |= static_cast<std::uint16_t>(1u << (3 * (qy - y + 1) + qx - x + 1));
        }
      smooth.plane(0)[s] = sum / static_cast<float>(n);  // n >= 1: the sample itself
      same[s] = bits;
    }
  });
  Image out(w, h, 1);
  const float* c = smooth.plane(0);
  // Sample centres sit at pixel (s + 1/2) scale: a pixel's place between them, per column and
  // per row (the same for every row and column), and the sample of its own block, which is one
  // of the two.
  struct Between {
    int first, second, own;
    float second_weight;
  };
  auto between = [&](int i, int samples) {
    const float t = (static_cast<float>(i) + 0.5f) / static_cast<float>(scale) - 0.5f;
    const int first = std::clamp(static_cast<int>(std::floor(t)), 0, samples - 1);
    return Between{first, std::min(first + 1, samples - 1), std::min(i / scale, samples - 1),
                   std::clamp(t - static_cast<float>(first), 0.0f, 1.0f)};
  };
  std::vector<Between> columns(w);
  for (int x = 0; x < w; ++x) columns[x] = between(x, gw);
  parallel_for_rows(h, [&](int y) {
    const Between row = between(y, gh);
    const int ys[2] = {row.first, row.second};
    const float wy[2] = {1.0f - row.second_weight, row.second_weight};
    for (int x = 0; x < w; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      const float z = depth.plane(0)[p];
      float& o = out.plane(0)[p];
      o = 0.0f;
      if (!std::isfinite(z)) continue;
      // The samples around the pixel on its own block's surface (and near its depth).
      const Between& col = columns[x];
      const std::size_t own = static_cast<std::size_t>(row.own) * gw + col.own;
      const int xs[2] = {col.first, col.second};
      const float wx[2] = {1.0f - col.second_weight, col.second_weight};
      float sum = 0, weight = 0;
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const std::size_t q = static_cast<std::size_t>(ys[j]) * gw + xs[i];
          const int bit = 3 * (ys[j] - row.own + 1) + xs[i] - col.own + 1;
          if (!(same[own] >> bit & 1u) || !near(gz[q], z)) continue;
          sum += wx[i] * wy[j] * c[q];
          weight += wx[i] * wy[j];
        }
      o = weight > 0 ? sum / weight : std::max(c[own], 0.0f);
    }
  });
  return out;
}

Image gather_bounces(const TraceGrid& grid, const HitSource& hits, int bounces,
                     const MissModel& misses, Image* coverage, CubeLight* last_cube) {
  // Each bounce's light per trace sample as a hit on its lit front brings it (what it reflects
  // plus albedo x its indirect light), packed RGB_ so that such a hit is one 16-byte load: 2 MB
  // at a 1080p frame's 480 x 270 grid, read at random. The few hits from behind bring its unseen
  // back (albedo x indirect only: surface_model.h), the same product of the grid's albedo and
  // the bounce before's light taken where they are read: a table of the backs beside the fronts
  // would double the fresh memory each frame and each bounce's writes for those few hits.
  const std::size_t n = grid.origin.size();
  UninitializedVector<std::array<float, 4>> light(n);
  parallel_for_rows(grid.height, [&](int by) {
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      light[s] = {grid.reflected.plane(0)[s], grid.reflected.plane(1)[s],
                  grid.reflected.plane(2)[s], 0.0f};
    }
  });
  // The light of the bounce before and the one being gathered, swapped after each bounce; 0
  // where the grid has no origin, which no gather writes.
  Image indirect(grid.width, grid.height, 3), next(grid.width, grid.height, 3);
  bool first = true;  // no bounce before: the backs are dark
  auto lookup = [&](std::int32_t hit) {
    if (hit >= kSeenFromBehind) {
      const std::size_t s = static_cast<std::size_t>(hit_pixel(hit));
      if (first) return std::array<float, 3>{0.0f, 0.0f, 0.0f};
      return std::array<float, 3>{grid.albedo.plane(0)[s] * indirect.plane(0)[s],
                                  grid.albedo.plane(1)[s] * indirect.plane(1)[s],
                                  grid.albedo.plane(2)[s] * indirect.plane(2)[s]};
    }
    const std::array<float, 4>& l = light[static_cast<std::size_t>(hit)];
    return std::array<float, 3>{l[0], l[1], l[2]};
  };
  CubeLight cube = misses.cube_light(grid, light.data());
  gather_once(grid, hits, lookup, cube, &next, bounces == 1 ? coverage : nullptr);
  std::swap(indirect, next);
  first = false;
  for (int b = 1; b < bounces; ++b) {
    parallel_for_rows(grid.height, [&](int by) {
      for (int bx = 0; bx < grid.width; ++bx) {
        const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
        for (int c = 0; c < 3; ++c)
          light[s][c] = grid.reflected.plane(c)[s] + grid.albedo.plane(c)[s] * indirect.plane(c)[s];
      }
    });
    cube = misses.cube_light(grid, light.data());
    gather_once(grid, hits, lookup, cube, &next, b + 1 == bounces ? coverage : nullptr);
    std::swap(indirect, next);
  }
  if (last_cube) *last_cube = cube;
  return indirect;
}

}  // namespace ssgi::detail
