// Missed rays continued through other traces of the same scene, their *sources*: a ray that
// leaves frame t, or passes behind everything t shows, meets nothing t can tell about, and the
// miss model guesses what it would meet. Other cameras show more: views rendered at the frame's
// own time (the six faces of a cube, a panorama: --view), and the other frames of the temporal
// window, which show what t does not when the camera moves (--multiframe). Each missed ray is
// marched on, from the same world-space point in the same world-space direction, through the
// depth buffer (trace grid) of the sources, each with its own camera; the surface it meets brings
// that source's own light there: what it reflects plus its albedo x the indirect light the
// source gathered itself (its unseen back only the latter, as in surface_model.h), so that
// lighting that changes over the shot stays right. Found rays leave the miss model's shares and
// bring their light, counted as traced.
//
// Geometry is taken as static: a surface a source shows where frame t sees past it (the point
// lies in front of t's own surface there by more than the slab, or t shows the background there)
// is a moving object, or was not there at t, and is not taken. The result depends on the
// sources alone, so chunked runs give the same bits as whole ones.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "buffers.h"
#include "gi/directions.h"
#include "gi/gather.h"
#include "gi/misses.h"
#include "ssgi/camera.h"
#include "ssgi/image.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

// One missed ray of a trace sample: a camera-space unit direction, its share of the sample's
// cosine-weighted hemisphere, and how far the frame sees it free: its parameter at the tracer's
// last sample before it first passes behind what the frame shows, or the infinite float when it
// does not while on the screen.
struct MissedRay {
  Imath::V3f direction;
  float weight;
  float hidden;
};
using PixelMisses = std::vector<MissedRay>;

// Rays per slice that carry its missed sectors on (trace_slices), each weighing its run of them.
// A found ray takes its own direction's shares of the miss model times its weight out of its
// sample's: its run's shares in the mean, but not face by face, so that on one cube face or the
// environment it can take out more than the sample holds there. Views take the shares out as
// they are (ContinuationPolicy::hold_shares_at_zero): a sample's can fall below zero, and the
// light is held at zero once denoised (FrameStages), so that the light is the same in the mean
// for any count of rays, and one ray per slice continues half the rays of two at the same error.
// The window's frames find few of a frame's rays: each share is held at zero, and two rays per
// slice keep that bias small. The views' choice is measured in tests/accuracy/README.md ("Views:
// the surroundings with their depth").
constexpr int kViewRunsPerSlice = 1;
constexpr int kMultiframeRunsPerSlice = 2;

// A frame's missed rays, per trace sample (the slice tracer records them, slices.h).
// (Resizing begin and rays leaves the new entries for the tracer to write, in parallel.)
struct MissedRays {
  UninitializedVector<std::uint32_t> begin;  // per trace sample, its first ray; one more at the end
  UninitializedVector<MissedRay> rays;
  std::vector<Imath::V3f> origin;  // per trace sample, where its rays start (camera space)
};

// A frame's trace: its trace grid (what other traces' rays meet there, and where its own start),
// its hits and misses, its missed rays and its camera.
struct FrameTrace {
  FrameTrace(int frame, const Camera& camera, TraceGrid grid, WeightedHits hits, MissModel misses,
             MissedRays missed);
  int frame;
  Camera camera;
  TraceGrid grid;
  WeightedHits hits;
  MissModel misses;
  MissedRays missed;
  // The reference tracer's hits, traced again for each bounce (reference.h; they need `misses`,
  // so the trace stays where it is made): null for the tracers that hold theirs in `hits`.
  std::shared_ptr<const HitSource> retraced;
  // Drops what only the frame's own continuation reads (its hits and missed rays), once it
  // is only a source of other frames'.
  void release_own();
};

// A source of a continuation: a trace, and its own indirect light on its trace grid (unread for
// --bounces 1, where a surface brings what it reflects alone).
struct ContinuationSource {
  const FrameTrace* trace;
  const Image* light;
};

// How rays are continued through a kind of source. Views show the scene at the frame's own time
// from the frame's camera position, all around it; the window's frames show it at other times,
// each much as the frame does.
struct ContinuationPolicy {
  enum class Kind { kViews, kFrames };
  Kind kind;
  // A ray takes the nearest surface any source shows on it (views: one time, one scene), or
  // the first surface found in the sources' order (frames: the nearest in time first, as it is
  // the likeliest to show the scene as frame t does).
  bool nearest;
  // Each source's segment of the ray is walked pixel by pixel: a view's few pixels each span
  // much of the scene, so that a segment sampled at --max-steps points steps past surfaces it
  // meets steeply (a ceiling's rays to the floor, found in the faces below it:
  // Views.EachFaceOfARoomLitOnItsFloorGetsItsShareOfTheFloor), and the walk, which skips the
  // empty space of the mesh's bounded quads, is no slower there than the samples.
  // The window's frames, as large as the frame, are sampled as its own march is.
  bool every_pixel;
  // A source's mesh also joins neighbours on one plane seen at a grazing angle
  // (DepthMesh::join_tangent_neighbours): a view's few pixels see much of the scene so.
  bool join_grazing;
  // A found ray's shares of the miss model are each held at zero when taken out of its sample's
  // (kMultiframeRunsPerSlice says why either).
  bool hold_shares_at_zero;
  // The views cover every direction around the camera: a ray that meets nothing they show,
  // where the first view holding its vanishing point shows no surface there, reaches the sky
  // (the environment's light); one that meets nothing else takes what lay behind it where it
  // was last seen (last_seen in continuation.cpp): a surface facing it, or the sky if it rises.
  // The window's frames see what the frame sees, and tell nothing of where a ray ends unseen.
  bool sky_and_last_seen;
};
// The policy of a kind of source: each choice follows from what the sources show.
ContinuationPolicy continuation_policy(ContinuationPolicy::Kind kind);

// The continuation's numbers for one frame (-v).
struct ContinuationReport {
  ContinuationPolicy::Kind kind = ContinuationPolicy::Kind::kViews;
  std::vector<int> sources;  // the frame numbers of the sources with a world transform, in order
  std::size_t rays = 0;      // missed rays continued (not seen free to their vanishing point)
  std::size_t found = 0;     // of those, the ones that met a surface a source shows
  std::size_t sky = 0;       // the ones that met none and reached the sky
  std::size_t hidden = 0;    // the ones that met none, last seen heading for a surface
  std::size_t refused = 0;   // rays that met only surfaces the frame sees past (not taken)
  std::string describe(int frame) const;
};

// A source's trace sample a ray was found to meet.
struct SourceHit {
  std::uint32_t source;  // its index among the sources given
  std::int32_t hit;      // a trace sample of it, kSeenFromBehind marked
  float weight;          // the ray's share of the hemisphere
};
struct SourceHits {
  std::vector<std::uint32_t> begin;  // per trace sample, its first; one more at the end
  std::vector<SourceHit> hits;
};

// What continuing a frame's missed rays gives.
struct Continuation {
  // False when no ray was continued (`shares` are then as given): the frame's camera or every
  // source's has no world transform, or the frame has no missed rays.
  bool walked = false;
  // The shares given, with the found rays' (and those reaching the sky) taken out, the light
  // they brought added to `continued_light`, the sky's light to `env`.
  MissShares shares;
  // With `keep_missed`: the rays still missed, for other sources to continue (their begin and
  // rays; their origins are the frame's own).
  MissedRays left;
  SourceHits found;  // with `record_found`: which source sample each found ray met
  ContinuationReport report;
  // Whether any ray met a surface, reached the sky or took a surface where it was last seen.
  bool changed() const { return report.found + report.sky + report.hidden > 0; }
};

// Continues the missed rays of `self` through `sources` under `policy`, each from where the
// frame stops seeing it free (off its edge, behind the camera, or behind what it shows), into
// `shares` (self's own, or what an earlier continuation left of them). A ray reaching the sky
// takes the environment's light into env.
Continuation continue_missed_rays(const FrameTrace& self, MissShares shares,
                                  const std::vector<ContinuationSource>& sources,
                                  const ContinuationPolicy& policy, const GiSettings& settings,
                                  bool keep_missed = false, bool record_found = false);

// continue_missed_rays on `t`'s own shares, put back into it with the rays still missed (none
// without `keep_missed`); returns the report and the found rays, its shares moved into `t`.
Continuation continue_into(FrameTrace* t, const std::vector<ContinuationSource>& sources,
                           const ContinuationPolicy& policy, const GiSettings& settings,
                           bool keep_missed = false, bool record_found = false);

// The light the rays `found` (continue_missed_rays, on `self`'s trace grid) bring from the same
// sources with their light now `light` (per source): what the continuation added to
// continued_light, for another pass of bounces among views.
Image source_light(const FrameTrace& self, const SourceHits& found,
                   const std::vector<ContinuationSource>& sources, const GiSettings& settings);

// The window's frames as the sources of frames[center]'s continuation: the others with a world
// transform and a camera unlike the centre's, nearest in frame number first (the earlier of two
// as near), each with its light; none when the centre's camera has no world transform.
std::vector<ContinuationSource> window_sources(const std::vector<const FrameTrace*>& frames,
                                               const std::vector<const Image*>& light, int center);

}  // namespace ssgi::detail
