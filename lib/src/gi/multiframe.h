// Rays continued in the other frames of the shot (--multiframe): a ray that leaves frame t, or
// passes behind everything t shows, meets nothing t can tell about, and the miss model
// guesses what it would meet. The temporal window reads frames t-k .. t+k anyway; when the
// camera moves they show what t does not (the floor beyond its edge, the wall behind the camera
// a moment ago, the surface behind an object). Each missed ray of t is marched again, from the
// same world-space point in the same world-space direction, through the depth buffer (trace
// grid) of each neighbour in turn, nearest frame first, with that frame's camera; the first
// surface found brings that frame's own light there: what it reflects plus its albedo x the
// indirect light that frame gathered itself (its unseen back only the latter, as in
// surface_model.h), so that lighting that changes over the shot stays right. Found rays leave
// the miss model's share and join the hits, and t's bounces are gathered again.
//
// Geometry is taken as static: a surface a neighbour shows where frame t sees past it (the
// point lies in front of t's own surface there by more than the slab, or t shows the background
// there) is a moving object, or was not there at t, and is not taken. Neighbours whose camera
// is t's own add nothing a moving object would not spoil, and are skipped. The result depends
// on the window's frames alone, so chunked runs give the same bits as whole ones.
#pragma once

#include <cstddef>
#include <cstdint>
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
// environment it can take out more than the sample holds there. The views take the shares out as
// they are (a sample's can fall below zero; the light is held at zero once denoised, FrameStages):
// the light is then the same in the mean for any count of rays, and one ray per slice continues
// half the rays of two at the same error. Six faces on the training set, 64 samples
// (tests/accuracy/views.sh): mean relRMSE 0.375 with one, 0.374 with two; with each share held at
// zero, 0.423 and 0.386, the mean level 17% and 7% higher. --multiframe holds each share at zero
// and keeps two: its neighbours find few of its rays (the shares as they are: mean relRMSE 0.404
// either way, level 1.004 against 1.012).
constexpr int kViewRunsPerSlice = 1;
constexpr int kMultiframeRunsPerSlice = 2;

// A frame's missed rays, per trace sample (the slice tracer records them, slices.h).
// (Resizing begin and rays leaves the new entries for the tracer to write, in parallel.)
struct MissedRays {
  UninitializedVector<std::uint32_t> begin;  // per trace sample, its first ray; one more at the end
  UninitializedVector<MissedRay> rays;
  std::vector<Imath::V3f> origin;  // per trace sample, where its rays start (camera space)
};

// The continuation's numbers for one frame (-v).
struct ContinuationReport {
  std::size_t rays = 0;     // missed rays continued (not seen free to their vanishing point)
  std::size_t found = 0;    // of those, the ones that met a surface there
  std::size_t moving = 0;   // rays that found surfaces, none taken: frame t sees past them
  std::vector<int> frames;  // the neighbours used, nearest first
  std::string describe(int frame) const;
};

// What a frame's trace keeps for the continuation: its trace grid (what the other frames' rays
// meet there, and where its own start), its hits and misses (its bounces are gathered again),
// its missed rays and its camera.
struct FrameTrace {
  FrameTrace(int frame, const Camera& camera, TraceGrid grid, WeightedHits hits, MissModel misses,
             MissedRays missed);
  int frame;
  Camera camera;
  TraceGrid grid;
  WeightedHits hits;
  MissModel misses;
  MissedRays missed;
  // Drops what only the frame's own continuation reads (its hits and missed rays), once it
  // is only another frame's neighbour.
  void release_own();
};

// The continuation's numbers for a frame's views (-v).
struct ViewsReport {
  int views = 0;            // views with a world transform (the others are not marched)
  std::size_t rays = 0;     // missed rays continued (not seen free to their vanishing point)
  std::size_t found = 0;    // of those, the ones that met a surface in a view
  std::size_t sky = 0;      // the ones that met none where a view shows the sky (shows_sky),
                            // or rising, last seen in front of it (last_seen)
  std::size_t hidden = 0;   // the ones that met none, last seen heading for a surface there
  std::size_t refused = 0;  // rays that met only surfaces the frame sees past (not taken)
  std::string describe(int frame) const;
};

// Views (--view): other cameras on the same scene at the frame's own time (the six faces of a
// cube or a panorama rendered at the camera, a wider overscan render), each lit as a frame is.
// Every missed ray of `*self` is marched on in the depth buffer of each view, from the same
// world-space point in the same direction, from where the frame stops seeing it free (off its
// edge, behind the camera, or behind what it shows), and takes the nearest surface any view
// shows on it, unless the frame sees past that point (as continue_rays refuses a moving object).
// The surface brings what it reflects plus its albedo x the view's own indirect light
// (`light`: per view, on its trace grid; unread for --bounces 1), as continue_rays' neighbours
// do. Into self->hits: that light per trace sample in `foreign` (added), the found rays' shares
// taken out of miss, env and cube; with `keep_missed`, self->missed keeps only the rays still
// missed, for the shot's other frames to continue (else it is emptied). A view's mesh also joins
// neighbours that lie on one plane seen at a grazing angle (DepthMesh::join_tangent_neighbours): a
// view's few pixels see much of the scene so. A ray that meets nothing any view shows, where
// the first view whose picture holds its vanishing point shows no surface there, reaches the
// sky: it takes the environment's light (into env) and its shares of the miss model are taken
// out as a found ray's are. One that meets nothing else takes what lay behind it where it was
// last seen (multiframe.cpp, last_seen): a surface facing it (its light, as a found ray's), or
// the sky if the ray rises; the rest are left to the miss model. True when a ray met a surface,
// reached the sky or took a surface so; nothing changes without a world transform for the
// frame's camera. With `found`, also which view sample each found
// ray met and its weight, for view_light.
struct ViewHit {
  std::uint32_t view;  // its index in `views`
  std::int32_t hit;    // a trace sample of it, kSeenFromBehind marked
  float weight;        // the ray's share of the hemisphere
};
struct ViewHits {
  std::vector<std::uint32_t> begin;  // per trace sample, its first; one more at the end
  std::vector<ViewHit> hits;
};
bool continue_in_views(FrameTrace* self, const std::vector<const FrameTrace*>& views,
                       const std::vector<const Image*>& light, const GiSettings& settings,
                       bool keep_missed, ViewsReport* report, ViewHits* found = nullptr);

// The light the rays `found` (continue_in_views, on `self`'s trace grid) bring from the same
// views with their light `light`: what continue_in_views adds to hits.foreign, for the views'
// light of another pass of bounces among them.
Image view_light(const FrameTrace& self, const ViewHits& found,
                 const std::vector<const FrameTrace*>& views,
                 const std::vector<const Image*>& light, const GiSettings& settings);

// Frame frames[center]'s light on its trace grid with its missed rays continued in the other
// frames (in ascending frame order, each with its own light on its grid, before any temporal
// filter), after `settings.bounces` gathers, into *out; with `coverage`, gather_bounces'
// coverage, a continued ray that found a surface counting as traced; with `shares`, the cube
// shares the rays still missed leave to the miss model (WeightedHits::cube). False, and nothing
// written, when nothing changed: no missed rays, no camera with a world transform, no
// neighbour whose camera differs from the centre's, or no continued ray found a surface.
bool continue_rays(const std::vector<const FrameTrace*>& frames,
                   const std::vector<const Image*>& light, int center, const GiSettings& settings,
                   Image* out, Image* coverage, Image* shares, ContinuationReport* report);

}  // namespace ssgi::detail
