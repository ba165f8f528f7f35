// Extra views of a shot's scene (--view, --latlong-view): other cameras on the same scene at the
// same time, such as the six faces of a cube or a lat-long panorama rendered at the shot camera,
// whose surfaces the frame's missed rays continue to (gi/continuation.h, continue_missed_rays). A
// view is read as a frame is (the shot's layout, --channel mapping and conventions; its own
// camera from its own header, its own resolution); a lat-long view becomes six pinhole cube
// faces, so that every view is marched alike.
#pragma once

#include <string>
#include <vector>

#include "io/color.h"
#include "io/sequence_info.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"

namespace ssgi::detail {

// Opens options.views against the shot `shot` (opened from `options`): each view's files probed
// from its first (a still's file, or the one of the shot's first frame), its camera read, and
// every file it has for the shot's frames opened (a header each), so that what is wrong with a
// view is said before anything is computed. Throws Error(kInput) naming the file for a view
// without a camera (a pinhole's worldToCamera and worldToNDC, or another camera ssgi reads; a
// lat-long's worldToCamera), or for a shot or view camera without a world transform (the views'
// light cannot be placed); Error(kIO) naming it for a missing or unreadable file of a frame
// the shot writes.
std::vector<ViewInfo> open_views(const SequenceInfo& shot, const InputOptions& options);

// Throws Error(kIO) naming the first file a view lacks for one of `frames` (those a run reads:
// the frames it writes and their temporal neighbours), before a run computes anything.
void check_views_cover(const SequenceInfo& shot, const std::vector<int>& frames);

// The views of frame `frame` of the shot, read with the shot's options and converted as a frame
// is (depth, normals, albedo, direct light, emission), each a pinhole G-buffer with a world
// transform: a lat-long view as its six cube faces (latlong_faces). Throws as read_gbuffer.
std::vector<GBuffer> read_views(const SequenceInfo& shot, int frame, const InputOptions& options,
                                const ColorManagement* color);

// A lat-long view (its camera Projection::kLatLong, depth the distance along each pixel's ray)
// as the six 90-degree faces of a cube at its camera, each `size` pixels square (0:
// latlong_face_size), looking along its camera's +z, -z, +x, -x, +y and -y: each face pixel takes
// the lat-long pixel its centre's direction falls in, its depth made planar in the face's camera,
// its normal turned into that camera's space.
std::vector<GBuffer> latlong_faces(const GBuffer& latlong, int size = 0);

// The side of a lat-long's faces: a quarter of its display window's width (at least 8).
int latlong_face_size(const Box2i& display_window);

}  // namespace ssgi::detail
