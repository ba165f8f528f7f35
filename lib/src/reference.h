// The Embree reference: hemisphere rays traced against a mesh built from the depth buffer with
// the same surface model as the march (surface_model.h), so that comparing `ssgi run` with
// `ssgi reference` measures the march and the denoiser and nothing else. Embree is used here
// and nowhere else.
#pragma once

// NOTE TO THE ENGINEER IMPLEMENTING THIS FILE (from the pipeline owner, written while you work):
// the surface model is changing from per-pixel slab boxes to the mesh the issue describes,
// because slab boxes make a tilted plane a staircase that shadows itself (a lone plane must
// give indirect = 0 exactly). The new model, in lib/src/surface_model.h (being rewritten now):
// a vertex at every surface pixel centre (unprojected at its planar depth), two triangles per
// 2x2 pixel quad with the fixed diagonal from (x, y) to (x+1, y+1), a triangle only where its
// three vertices are pairwise `connected` (each within the other's slab: the thickness rule);
// the slab behind the surface is the same mesh scaled by (1 + thickness) about the camera
// centre (vertex depths z * (1 + T)), closed by side walls along mesh boundary edges. A ray
// hits pixel P's light when it enters the slab volume of a triangle; the hit's light is that of
// the triangle's vertex with the largest barycentric weight at the hit point (ties: the
// vertex that comes first in the order (x,y), (x+1,y), (x,y+1), (x+1,y+1)).
// Please build the Embree reference from this mesh, not from pixel boxes, and do not edit
// lib/src/march.cpp or surface_model.h: the pipeline owner is changing the march to the same
// model right now.

#include "environment.h"
#include "march.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// Traces settings.rays cosine-weighted rays per surface pixel with Embree and records, like
// march_screen_space, the hit pixel of each ray or a miss (with the environment it saw).
RayHits trace_reference(const GBuffer& g, const GiSettings& settings, const Environment& env);

}  // namespace ssgi::detail
