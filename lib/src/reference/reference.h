// The Embree reference: hemisphere rays traced with Embree against the surface model of
// surface_model.h, so that comparing `ssgi run` with `ssgi reference` measures the march and the
// denoiser and nothing else. Embree is used here and nowhere else.
//
// The reference mesh is the closed surface of the slab volume: for every triangle of the depth
// mesh (a vertex at each surface pixel centre at its planar depth, two triangles per 2x2 quad of
// pixel centres with the diagonal (x, y)-(x+1, y+1), only where the three vertices are pairwise
// connected), its front face, its back face (the same triangle at depths x (1 + thickness)), and
// along each boundary edge of the mesh a wall joining the two. Every face points out of the
// volume, so a hit tells whether the ray enters or leaves it.
//
// A ray brings the light of the first point on it that is inside the volume and outside its own
// pixel's square on the screen (the march skips samples in its own pixel): the point where it
// enters the volume, or where counting starts if it is inside by then (it set out inside, or
// leaves its own pixel inside). That light is the pixel DepthMesh::surface_at names there: the
// vertex of the triangle with the largest screen-space barycentric weight.
#pragma once

#include <cstddef>
#include <memory>

#include "gi/environment.h"
#include "gi/gather.h"
#include "gi/march.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// Traces settings.rays rays per surface pixel with Embree and records, like march_screen_space,
// the pixel whose light each ray brings or a miss (with what `misses` gives it). The rays are
// the march's: the same origins and the same cosine-weighted directions from the pixel's
// rotated R2 set (directions.h), so ray k of the reference is ray k of the march. MissMode::kExtend
// has no meaning here (there is no screen edge beyond which to extend a surface): its model sends
// every miss to the environment, as with kEnvironment. The result is the same for any thread
// count. Throws Error(kInternal) when Embree fails.
RayHits trace_reference(const GBuffer& g, const GiSettings& settings, const MissModel& misses);

// The same rays' hits for the bounce loop (gather.h, at trace scale 1), in bounded memory: a
// row is traced when the first bounce gathers it; the first rows whose hits fit in
// `budget_bytes` keep them for the later bounces, the others are traced again for each. The
// same rays meet the same pixels, so the light does not depend on the budget, only the time:
// a tracing per bounce for the rows not kept. Besides the kept hits it holds the Embree scene
// and 16 bytes per pixel. Throws Error(kInternal) when Embree fails.
class ReferenceHits final : public HitSource {
 public:
  // `misses` must outlive it.
  ReferenceHits(const GBuffer& g, const GiSettings& settings, const MissModel& misses,
                std::size_t budget_bytes);
  ~ReferenceHits() override;
  HitRow row(int by, HitScratch* scratch) const override;
  const Image& miss() const override;
  const Image& env() const override;
  const Image& cube() const override;

  // The most a row's kept hits take: 4 bytes per ray, 4 per pixel.
  static std::size_t row_bytes(int width, int rays);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ssgi::detail
