#include "io/views.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "io/input_frame.h"
#include "io/sequence.h"
#include "log.h"
#include "parallel.h"
#include "throw.h"

namespace ssgi {

std::string ViewInfo::path_for(int frame) const {
  return still ? pattern : sequence->pattern.path_for(frame);
}

namespace detail {

int latlong_face_size(const Box2i& display_window) {
  return std::max(8, (display_window.width() + 2) / 4);
}

namespace {

namespace fs = std::filesystem;

// How a view's files are read: the shot's options (layout, --channel, conventions, --normals)
// with the view's own camera and nothing of the shot's frames, context or views.
InputOptions view_options(const InputOptions& shot, const ViewOptions& view) {
  InputOptions o = shot;
  o.pattern = view.pattern;
  o.frames.clear();
  o.skip_missing = false;
  o.camera = CameraOptions();
  o.camera.projection = view.projection;
  o.context.clear();
  o.views.clear();
  return o;
}

const char* option_of(const ViewOptions& view) {
  return view.projection == Projection::kLatLong ? "--latlong-view" : "--view";
}

// A cube face's camera axes in the lat-long camera's space: right, up and forward, right = up x
// forward as in the library's camera space (x right, y up, +z forward).
struct FaceAxes {
  Imath::V3d right, up, forward;
};

FaceAxes face_axes(int face) {
  static const Imath::V3d kForward[6] = {{0, 0, 1},  {0, 0, -1}, {1, 0, 0},
                                         {-1, 0, 0}, {0, 1, 0},  {0, -1, 0}};
  static const Imath::V3d kUp[6] = {{0, 1, 0}, {0, 1, 0},  {0, 1, 0},
                                    {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  FaceAxes a;
  a.forward = kForward[face];
  a.up = kUp[face];
  a.right = a.up.cross(a.forward);
  return a;
}

}  // namespace

std::vector<ViewInfo> open_views(const SequenceInfo& shot, const InputOptions& options) {
  const int first_frame = shot.frames.front();
  // The views' light is placed through the cameras' world transforms: the shot's must have one.
  const Camera shot_camera = read_camera(shot, first_frame, options);
  if (!shot_camera.has_world_transform)
    throw_input(shot.pattern.path_for(first_frame),
                "its camera (" + shot_camera.source +
                    ") has no world transform, which --view needs to place the views' light: "
                    "give the header's camera, a --camera sidecar with worldToCamera, or a "
                    "position pass");
  std::vector<ViewInfo> out;
  for (const ViewOptions& v : options.views) {
    ViewInfo info;
    info.pattern = v.pattern;
    info.projection = v.projection;
    info.still = !parse_sequence_pattern(v.pattern).has_frame_field;
    InputOptions o = view_options(options, v);
    if (info.still) {
      if (!fs::exists(v.pattern))
        throw_io(v.pattern, std::string(option_of(v)) +
                                ": no such file (the preview's OCIO view is --display-view)");
    } else {
      o.frames = std::to_string(first_frame);
    }
    SequenceInfo seq;
    try {
      seq = open_view_sequence(o);
    } catch (const Error& e) {
      throw Error(e.kind(), e.file(), std::string(option_of(v)) + ": " + e.what());
    }
    if (info.still) {
      // The file itself, whatever digits its name holds.
      seq.pattern = SequencePattern();
      seq.pattern.prefix = v.pattern;
      seq.frames_on_disk = seq.frames = {first_frame};
    }
    const std::string first = info.still ? v.pattern : seq.pattern.path_for(first_frame);
    if (v.projection == Projection::kLatLong && seq.normals_from_depth)
      throw_input(first, "has no normal channels, which a lat-long view needs");
    for (const Role role : {Role::kDepth, Role::kAlbedo, Role::kDirect})
      if (!seq.layout.has(role))
        throw_input(first, std::string(option_of(v)) + ": has no " + role_name(role) +
                               " channels, which a view needs (its surfaces, and the light they "
                               "reflect)");
    Camera camera;
    try {
      camera = read_camera(seq, first_frame, o);
    } catch (const Error& e) {
      throw Error(e.kind(), e.file(), std::string(option_of(v)) + ": " + e.what());
    }
    if (!camera.has_world_transform)
      throw_input(first, std::string(option_of(v)) + ": its camera (" + camera.source +
                             ") has no world transform");
    if (v.projection == Projection::kLatLong) {
      const Box2i& d = seq.display_window;
      if (d.width() != 2 * d.height())
        log_warning(first +
                    ": a lat-long view covers 360 x 180 degrees, but its display window "
                    "is " +
                    std::to_string(d.width()) + " x " + std::to_string(d.height()) +
                    " (not 2:1): its pixels are not square");
    }
    info.sequence = std::make_shared<const SequenceInfo>(std::move(seq));
    out.push_back(std::move(info));
  }
  // Every file the frames written read, opened now: a missing or unreadable one is said before
  // anything is written.
  for (const ViewInfo& view : out) {
    for (int f : view.still ? std::vector<int>{first_frame} : shot.frames) {
      const std::string path = view.path_for(f);
      if (!fs::exists(path))
        throw_io(path,
                 "frame " + std::to_string(f) + " of the view " + view.pattern + " is missing");
      open_input_exr(path);
    }
  }
  return out;
}

void check_views_cover(const SequenceInfo& shot, const std::vector<int>& frames) {
  for (const ViewInfo& view : shot.views) {
    if (view.still) continue;
    for (int f : frames) {
      const std::string path = view.path_for(f);
      if (!fs::exists(path))
        throw_io(path, "frame " + std::to_string(f) + " of the view " + view.pattern +
                           " is missing: a view covers every frame the run reads (those it "
                           "writes and their temporal neighbours)");
    }
  }
}

std::vector<GBuffer> read_views(const SequenceInfo& shot, int frame, const InputOptions& options,
                                const ColorManagement* color) {
  std::vector<GBuffer> out;
  for (std::size_t i = 0; i < shot.views.size(); ++i) {
    const ViewInfo& view = shot.views[i];
    const SequenceInfo& seq = *view.sequence;
    const InputOptions o = view_options(options, options.views[i]);
    RoleMask roles = role_bit(Role::kDepth) | role_bit(Role::kNormal) | role_bit(Role::kAlbedo) |
                     role_bit(Role::kDirect);
    if (seq.layout.has(Role::kEmission)) roles |= role_bit(Role::kEmission);
    GBuffer g =
        read_input_frame(seq, view.still ? seq.frames.front() : frame, roles, o, color, false).g;
    g.frame = frame;
    if (view.projection == Projection::kLatLong) {
      for (GBuffer& face : latlong_faces(g)) out.push_back(std::move(face));
    } else {
      out.push_back(std::move(g));
    }
  }
  return out;
}

std::vector<GBuffer> latlong_faces(const GBuffer& ll, int size) {
  const int w = ll.width(), h = ll.height();
  if (size <= 0) size = latlong_face_size(ll.display_window);
  const Camera& cam = ll.camera;
  const double half = size / 2.0;
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<GBuffer> faces;
  for (int f = 0; f < 6; ++f) {
    const FaceAxes a = face_axes(f);
    GBuffer g;
    g.path = ll.path;
    g.frame = ll.frame;
    g.display_window = g.data_window = Box2i{0, 0, size, size};
    g.normals_source = ll.normals_source;
    g.camera.fx = g.camera.fy = half;
    g.camera.cx = g.camera.cy = half;
    g.camera.has_world_transform = ll.camera.has_world_transform;
    g.camera.source = ll.camera.source + ", cube face " + std::to_string(f + 1) + " of 6";
    // Lat-long camera space to the face's (row vectors: p_face = p_ll M).
    Imath::M44d m;
    for (int i = 0; i < 3; ++i) {
      m[i][0] = a.right[i];
      m[i][1] = a.up[i];
      m[i][2] = a.forward[i];
    }
    g.camera.world_to_camera = ll.camera.world_to_camera * m;
    g.depth = Image(size, size, 1);
    g.normal = Image(size, size, 3);
    g.albedo = Image(size, size, 3);
    g.direct = Image(size, size, 3);
    if (!ll.emission.empty()) g.emission = Image(size, size, 3);
    parallel_for_rows(size, [&](int y) {
      for (int x = 0; x < size; ++x) {
        // The pixel centre's direction in the face's camera, then in the lat-long's.
        const double u = (x + 0.5 - half) / half, v = (half - (y + 0.5)) / half;
        const Imath::V3d d = a.right * u + a.up * v + a.forward;
        double px, py;
        cam.project(d, &px, &py);
        // The panorama pixel (the display window's edges hold longitude +-180 and latitude
        // +-90), in its data window: a hole where the data window does not reach.
        const int dx =
            std::clamp(static_cast<int>(std::floor(px)), 0, ll.display_window.width() - 1);
        const int dy =
            std::clamp(static_cast<int>(std::floor(py)), 0, ll.display_window.height() - 1);
        const int lx = dx + ll.display_window.x0 - ll.data_window.x0;
        const int ly = dy + ll.display_window.y0 - ll.data_window.y0;
        const bool inside = lx >= 0 && ly >= 0 && lx < w && ly < h;
        // Planar depth in the face: the distance along the direction (u, v, 1) of length |d|.
        const double z =
            inside ? static_cast<double>(ll.depth.at(0, lx, ly)) / std::sqrt(d.dot(d)) : 0.0;
        if (!(std::isfinite(z) && z > 0)) {
          g.depth.at(0, x, y) = inf;  // no surface: normal, albedo and light stay 0
          continue;
        }
        g.depth.at(0, x, y) = static_cast<float>(z);
        const Imath::V3d n{ll.normal.at(0, lx, ly), ll.normal.at(1, lx, ly),
                           ll.normal.at(2, lx, ly)};
        g.normal.at(0, x, y) = static_cast<float>(n.dot(a.right));
        g.normal.at(1, x, y) = static_cast<float>(n.dot(a.up));
        g.normal.at(2, x, y) = static_cast<float>(n.dot(a.forward));
        for (int c = 0; c < 3; ++c) {
          g.albedo.at(c, x, y) = ll.albedo.at(c, lx, ly);
          g.direct.at(c, x, y) = ll.direct.at(c, lx, ly);
          if (!ll.emission.empty()) g.emission.at(c, x, y) = ll.emission.at(c, lx, ly);
        }
      }
    });
    faces.push_back(std::move(g));
  }
  return faces;
}

}  // namespace detail
}  // namespace ssgi
