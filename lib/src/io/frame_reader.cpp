// Reading renderer EXR sequences into the library's G-buffer.
#include "io/frame_reader.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <regex>

#include "io/camera.h"
#include "io/camera_fit.h"
#include "io/camera_header.h"
#include "io/color.h"
#include "io/guide.h"
#include "io/input_frame.h"
#include "io/oiio_files.h"
#include "io/pass_agreement.h"
#include "io/views.h"
#include "log.h"
#include "parallel.h"
#include "ssgi/plan.h"
#include "throw.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

// Opens an input frame: an OpenEXR file or a clear error.
std::unique_ptr<OIIO::ImageInput> open_exr(const std::string& path) {
  auto in = detail::open_image(path);
  if (std::string(in->format_name()) != "openexr")
    throw_io(path, std::string("not an OpenEXR file (") + in->format_name() + ")");
  return in;
}

Box2i display_window_of(const OIIO::ImageSpec& spec) {
  return {spec.full_x, spec.full_y, spec.full_x + spec.full_width, spec.full_y + spec.full_height};
}

Box2i data_window_of(const OIIO::ImageSpec& spec) {
  return {spec.x, spec.y, spec.x + spec.width, spec.y + spec.height};
}

FileChannels probe_channels(OIIO::ImageInput& in) {
  FileChannels file;
  for (int s = 0; in.seek_subimage(s, 0); ++s) {
    const OIIO::ImageSpec& spec = in.spec();
    file.subimage_names.push_back(spec.get_string_attribute("oiio:subimagename"));
    file.channels.push_back(spec.channelnames);
    if (s == 0) {
      for (const OIIO::ParamValue& p : spec.extra_attribs)
        file.attributes[p.name().string()] = p.get_string();
    }
  }
  in.seek_subimage(0, 0);
  return file;
}

// A plain file name ending in digits (`shot.0005.exr`) is frame 5 of `shot.####.exr`, so a
// single-file run keys its noise to the same frame as a sequence run would.
SequencePattern pattern_for_single_file(const std::string& name, std::vector<int>* frames) {
  static const std::regex kTrailingFrame(R"(^(.*[._])(-?)([0-9]+)(\.[A-Za-z0-9]+)$)");
  std::smatch m;
  SequencePattern pattern;
  if (std::regex_match(name, m, kTrailingFrame) && m[3].length() <= 9) {
    pattern.prefix = m[1];
    pattern.suffix = m[4];
    pattern.padding = static_cast<int>(m[3].length());
    pattern.has_frame_field = true;
    const int frame = std::stoi(m[3]);
    frames->assign(1, m[2].length() ? -frame : frame);
  } else {
    pattern.prefix = name;
    frames->assign(1, 0);
  }
  return pattern;
}

void check_windows(const SequenceInfo& seq, const OIIO::ImageSpec& spec, const std::string& path) {
  const Box2i display = display_window_of(spec);
  const Box2i data = data_window_of(spec);
  if (data.empty()) throw_input(path, "data window is empty (zero pixels)");
  if (display != seq.display_window)
    throw_input(path, "display window " + std::to_string(display.width()) + "x" +
                          std::to_string(display.height()) + " differs from the first frame's " +
                          std::to_string(seq.display_window.width()) + "x" +
                          std::to_string(seq.display_window.height()));
  if (data != seq.data_window) throw_input(path, "data window differs from the first frame's");
}

// Values beyond this are clamped: sums of a few thousand of them stay finite in float.
constexpr float kHuge = 1e30f;

float finite_or(float v, float nan_value) {
  if (std::isnan(v)) return nan_value;
  return std::clamp(v, -kHuge, kHuge);
}

// A NaN or infinite value of a normal, colour or beauty plane is a broken sample, not light or
// colour: it becomes 0 and is counted, so that nothing downstream sees it; values beyond kHuge
// are clamped. Returns the count.
std::size_t sanitize(Image* image) {
  const int w = image->width();
  std::vector<std::size_t> per_row(image->height(), 0);
  detail::parallel_for_rows(image->height(), [&](int y) {
    for (int c = 0; c < image->channels(); ++c) {
      float* row = image->plane(c) + static_cast<std::size_t>(y) * w;
      for (int x = 0; x < w; ++x) {
        const float v = row[x];
        if (std::isfinite(v)) {
          row[x] = std::clamp(v, -kHuge, kHuge);
        } else {
          row[x] = 0.0f;
          ++per_row[y];
        }
      }
    }
  });
  std::size_t count = 0;
  for (std::size_t n : per_row) count += n;
  return count;
}

// Reads the channels of `targets` of one subimage into their planes (the frame's data window).
using FillChannels =
    std::function<void(int subimage, const std::vector<detail::PlaneTarget>& targets)>;

// A frame's channels: their names per subimage, and how to read them.
struct FrameChannels {
  const std::vector<std::vector<std::string>>& names;
  const FillChannels& fill;
};

// Per subimage, the names of channels to read and the planes they go to.
using NamedPlanes = std::map<int, std::vector<std::pair<std::string, float*>>>;

// Reads `planes` through `fill`, each subimage's channels found by name among
// `channel_names[subimage]`. Throws Error(kInput) naming `path` when a subimage or a channel
// is not there.
void fill_named_planes(const NamedPlanes& planes, const FrameChannels& channels,
                       const std::string& path) {
  const std::vector<std::vector<std::string>>& channel_names = channels.names;
  for (const auto& [subimage, names] : planes) {
    if (subimage < 0 || subimage >= static_cast<int>(channel_names.size()))
      throw_input(path, "has no subimage " + std::to_string(subimage));
    const std::vector<std::string>& present = channel_names[subimage];
    std::vector<detail::PlaneTarget> targets;
    for (const auto& [name, plane] : names) {
      const auto it = std::find(present.begin(), present.end(), name);
      if (it == present.end()) throw_input(path, "has no channel '" + name + "'");
      targets.push_back({static_cast<int>(it - present.begin()), plane});
    }
    // A part with a data window of its own (Nuke writes each part's bounding box) gives its
    // pixels where they fall in the frame's window, 0 elsewhere, as OpenEXR reads pixels
    // outside a data window.
    channels.fill(subimage, targets);
  }
}

// The name of a role's pass in messages: its layer ("ViewLayer.Position"), else its part, else
// its channels.
std::string pass_name(const SequenceInfo& seq, Role role) {
  const std::vector<ChannelRef>& refs = seq.layout.channels(role);
  const std::string& first = refs.front().name;
  const std::size_t dot = first.rfind('.');
  if (dot != std::string::npos && dot > 0) return first.substr(0, dot);
  const std::string& part = seq.channels.subimage_names[refs.front().subimage];
  if (!part.empty()) return part;
  std::string names;
  for (const ChannelRef& r : refs) names += (names.empty() ? "" : ",") + r.name;
  return names;
}

// A frame's position pass and where its surfaces are, read for the camera fit or the check of a
// header camera against it: positions (X, Y, Z) and a distance along the view (the stored depth
// in its kind's sense: planar or radial, any unit), +inf where the depth says background.
struct PositionPlanes {
  Image position, distance;
};

PositionPlanes read_position_planes(const SequenceInfo& seq, const FrameChannels& channels,
                                    const std::string& path) {
  const int w = seq.data_window.width(), h = seq.data_window.height();
  PositionPlanes p{Image(w, h, 3), Image(w, h, 1)};
  NamedPlanes planes;
  const std::vector<ChannelRef>& pos = seq.layout.channels(Role::kPosition);
  for (int c = 0; c < 3; ++c)
    planes[pos[c].subimage].emplace_back(pos[c].name, p.position.plane(c));
  const ChannelRef& depth = seq.layout.channels(Role::kDepth).front();
  planes[depth.subimage].emplace_back(depth.name, p.distance.plane(0));
  fill_named_planes(planes, channels, path);
  const LayoutPreset& preset = seq.layout.preset;
  const float inf = std::numeric_limits<float>::infinity();
  for (float& d : p.distance.data()) {
    double z = d;
    if (preset.depth_kind == DepthKind::kNegativeZ) z = -z;
    if (preset.depth_kind == DepthKind::kInverseZ) z = z > 0 ? 1 / z : inf;
    // Radial distance is compared with the planar background as convert_depth does after
    // turning it planar: a background written as 1e10 is far beyond either.
    d = std::isfinite(z) && z > 0 && z < preset.background_depth ? static_cast<float>(z) : inf;
  }
  return p;
}

// The camera of one frame: the sidecar, --fov, the header, and failing those a fit to the
// position pass (read through `channels`; without them, or without a position pass, no camera).
Camera find_camera(const SequenceInfo& seq, const InputOptions& options,
                   const OIIO::ImageSpec& spec, int frame, const std::string& path,
                   const FrameChannels* channels) {
  const Box2i& display = seq.display_window;
  if (options.camera.projection == Projection::kLatLong) {
    if (auto camera = detail::latlong_camera_from_header(spec, display, path)) return *camera;
    throw_input(path, "no camera: a lat-long view needs worldToCamera in its header");
  }
  if (!options.camera.sidecar.empty())
    return detail::camera_from_sidecar(options.camera.sidecar, frame, display);
  if (options.camera.hfov_deg > 0)
    return camera_from_fov(options.camera.hfov_deg, display, seq.pixel_aspect);
  if (auto camera = detail::camera_from_header(spec, display, path)) return *camera;
  if (!seq.layout.has(Role::kPosition) || !seq.layout.has(Role::kDepth))
    throw_input(path,
                "no camera: the header has no worldToCamera/worldToNDC; give --fov or --camera");
  if (!channels)
    throw_input(path, "no camera in the header: it is fitted to the position pass when read");
  const PositionPlanes planes = read_position_planes(seq, *channels, path);
  std::size_t lattice = 0;
  const std::vector<detail::PositionSample> samples = detail::position_samples(
      planes.position, planes.distance, display, seq.data_window, &lattice);
  detail::CameraFitResult fit =
      detail::fit_camera_to_positions(samples, lattice, pass_name(seq, Role::kPosition));
  if (!fit.ok) throw_input(path, "no camera in the header, and its " + fit.problem);
  return fit.camera;
}

// Where the first frame has a header camera and a position pass, warns when the two disagree
// by more than a pixel (RMS distance of the positions, projected by the header camera, from
// their pixel centres): a header written for another frame or resolution, or positions not in
// world space. Silent when they agree, as in frames whose header was written from the camera
// that rendered them, and when the positions are in the header camera's camera space.
void check_header_camera_against_positions(const SequenceInfo& seq, const InputOptions& options,
                                           OIIO::ImageInput& in, const std::string& path) {
  if (!options.camera.sidecar.empty() || options.camera.hfov_deg > 0) return;
  if (!seq.layout.has(Role::kPosition) || !seq.layout.has(Role::kDepth)) return;
  std::optional<Camera> camera;
  try {
    camera = detail::camera_from_header(in.spec(), seq.display_window, path);
  } catch (const Error&) {
    return;  // reading the frame reports it
  }
  if (!camera || !camera->has_world_transform) return;
  const FillChannels fill = [&](int subimage, const std::vector<detail::PlaneTarget>& targets) {
    detail::read_float_channels(in, subimage, targets, seq.data_window, path);
  };
  const PositionPlanes planes = read_position_planes(seq, {seq.channels.channels, fill}, path);
  const std::vector<detail::PositionSample> samples = detail::position_samples(
      planes.position, planes.distance, seq.display_window, seq.data_window);
  if (samples.empty()) return;
  // A pixel: below it the two agree as closely as a filtered position pass can show.
  constexpr double kAgreePx = 1.0;
  const double rms = detail::reprojection_rms_px(*camera, samples, seq.display_window);
  if (rms <= kAgreePx) return;
  // A position pass in camera space (RenderMan's "current" space) agrees with the header's
  // projection alone.
  Camera camera_space = *camera;
  camera_space.world_to_camera = Imath::M44d();
  if (detail::reprojection_rms_px(camera_space, samples, seq.display_window) <= kAgreePx) return;
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", rms);
  log_warning(path + ": the header camera (" + camera->source + ") and the position pass " +
              pass_name(seq, Role::kPosition) + " disagree by " + text +
              " px RMS; the header camera is used");
}

// Where the first frame has a depth pass, a position pass and a camera with a world transform,
// warns when the depth is not the kind of distance the layout says (planar or along the ray) or
// its background value reads as a surface, by the positions.
void check_depth_against_positions(const SequenceInfo& seq, const InputOptions& options,
                                   OIIO::ImageInput& in, const std::string& path) {
  if (!seq.layout.has(Role::kPosition) || !seq.layout.has(Role::kDepth)) return;
  const FillChannels fill = [&](int subimage, const std::vector<detail::PlaneTarget>& targets) {
    detail::read_float_channels(in, subimage, targets, seq.data_window, path);
  };
  const FrameChannels channels{seq.channels.channels, fill};
  Camera camera;
  try {
    camera = find_camera(seq, options, in.spec(), seq.frames.front(), path, &channels);
  } catch (const Error&) {
    return;  // reading the frame reports it
  }
  if (!camera.has_world_transform) return;
  const int w = seq.data_window.width(), h = seq.data_window.height();
  Image position(w, h, 3), depth(w, h, 1);
  NamedPlanes planes;
  const std::vector<ChannelRef>& pos = seq.layout.channels(Role::kPosition);
  for (int c = 0; c < 3; ++c) planes[pos[c].subimage].emplace_back(pos[c].name, position.plane(c));
  const ChannelRef& depth_channel = seq.layout.channels(Role::kDepth).front();
  planes[depth_channel.subimage].emplace_back(depth_channel.name, depth.plane(0));
  fill_named_planes(planes, channels, path);
  const LayoutPreset& preset = seq.layout.preset;
  const std::string problem = detail::depth_position_mismatch(
      depth, position, camera, preset.depth_kind, preset.background_depth, depth_channel.name,
      pass_name(seq, Role::kPosition));
  if (!problem.empty()) log_warning(path + ": " + problem);
}

// What the depth conversion found, for the warning about frames without surfaces.
struct DepthCounts {
  std::size_t surface = 0;   // pixels with a surface in front of the camera
  std::size_t negative = 0;  // finite stored values below 0
  std::size_t positive = 0;  // finite stored values above 0
};

// Planar camera z from the stored depth; +inf where there is no surface.
DepthCounts convert_depth(Image& depth, DepthKind kind, double background, const Camera& camera,
                          const Box2i& display, const Box2i& data) {
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<DepthCounts> per_row(depth.height());
  detail::parallel_for_rows(depth.height(), [&](int y) {
    DepthCounts& counts = per_row[y];
    for (int x = 0; x < depth.width(); ++x) {
      float& d = depth.at(0, x, y);
      const float v = d;
      double z = v;
      switch (kind) {
        case DepthKind::kPlanarZ:
          break;
        case DepthKind::kNegativeZ:
          z = -static_cast<double>(v);
          break;
        case DepthKind::kInverseZ:
          z = v > 0 ? 1.0 / v : inf;
          break;
        case DepthKind::kRadial: {
          if (camera.projection == Projection::kLatLong) break;  // the distance is its depth
          const double px = x + data.x0 - display.x0 + 0.5;
          const double py = y + data.y0 - display.y0 + 0.5;
          z = static_cast<double>(v) * camera.view_dir(px, py).z;
          break;
        }
      }
      // Below float's smallest normal number 1/z overflows: no surface is that close.
      const bool surface = std::isfinite(z) && z >= std::numeric_limits<float>::min() &&
                           z < background && std::isfinite(v);
      d = surface ? static_cast<float>(z) : inf;
      counts.surface += surface;
      counts.negative += std::isfinite(v) && v < 0;
      counts.positive += std::isfinite(v) && v > 0;
    }
  });
  DepthCounts counts;
  for (const DepthCounts& row : per_row) {
    counts.surface += row.surface;
    counts.negative += row.negative;
    counts.positive += row.positive;
  }
  return counts;
}

// A frame in which (almost) nothing is a surface gets no GI: usually a wrong --depth-kind or
// depth channel rather than an empty shot, so it is said, once per frame.
void warn_if_no_surfaces(const DepthCounts& counts, std::size_t pixels, DepthKind kind,
                         const std::string& path) {
  if (counts.surface * 1000 >= pixels) return;
  std::string why;
  if (kind == DepthKind::kNegativeZ && counts.positive > counts.negative)
    why = ": its depths are positive but --depth-kind is negative";
  else if (kind != DepthKind::kNegativeZ && counts.negative > counts.positive)
    why = ": its depths are negative (--depth-kind negative?)";
  log_warning(path + ": " + std::to_string(counts.surface) + " of " + std::to_string(pixels) +
              " pixels have a surface, the rest get no GI" + why);
}

// Unit camera-space normals facing the camera. World-space normals go through the inverse
// transpose of worldToCamera (row-vector convention: n' = n * inverse(M)^T). A zero, NaN or
// back-facing normal is replaced by (or flipped towards) the direction to the camera, so that
// every surface pixel has a usable hemisphere.
void convert_normals(Image& normal, const Image& depth, NormalSpace space, const Camera& camera,
                     const Box2i& display, const Box2i& data) {
  const bool to_camera = space == NormalSpace::kWorld && camera.has_world_transform;
  const bool flip_z = space == NormalSpace::kCameraGl;
  Imath::M44d inv;
  if (to_camera) inv = inverse_checked(camera.world_to_camera);
  detail::parallel_for_rows(normal.height(), [&](int y) {
    for (int x = 0; x < normal.width(); ++x) {
      if (!std::isfinite(depth.at(0, x, y))) {
        for (int c = 0; c < 3; ++c) normal.at(c, x, y) = 0.0f;
        continue;
      }
      Imath::V3d n{normal.at(0, x, y), normal.at(1, x, y), normal.at(2, x, y)};
      if (to_camera) {
        n = {n.x * inv[0][0] + n.y * inv[0][1] + n.z * inv[0][2],
             n.x * inv[1][0] + n.y * inv[1][1] + n.z * inv[1][2],
             n.x * inv[2][0] + n.y * inv[2][1] + n.z * inv[2][2]};
      }
      if (flip_z) n.z = -n.z;
      const Imath::V3d view =
          camera.view_dir(x + data.x0 - display.x0 + 0.5, y + data.y0 - display.y0 + 0.5);
      const double len = std::sqrt(n.dot(n));
      if (!(len > 1e-6) || !std::isfinite(len)) {
        n = -view;
      } else {
        n /= len;
        if (n.dot(view) > 0) n = -n;
      }
      normal.at(0, x, y) = static_cast<float>(n.x);
      normal.at(1, x, y) = static_cast<float>(n.y);
      normal.at(2, x, y) = static_cast<float>(n.z);
    }
  });
}

// Motion in the library's convention, in place: display pixels, +y down, offsets to frame -1
// (motion_prev) and +1 (motion_next). `xy` and `zw` hold the stored channels (zw: the third
// and fourth, or none).
void convert_motion(Image xy, Image zw, const MotionConvention& mc, const Box2i& display,
                    GBuffer* g) {
  const double sx = mc.in_ndc ? display.width() : mc.scale;
  const double sy = (mc.in_ndc ? display.height() : mc.scale) * (mc.y_up ? -1.0 : 1.0);
  const std::size_t n = xy.plane_size();
  for (std::size_t p = 0; p < n; ++p) {
    xy.plane(0)[p] = static_cast<float>((finite_or(xy.plane(0)[p], 0.0f) + mc.offset) * sx);
    xy.plane(1)[p] = static_cast<float>((finite_or(xy.plane(1)[p], 0.0f) + mc.offset) * sy);
  }
  if (mc.xy_to_previous) {
    g->motion_prev = std::move(xy);
  } else {
    g->motion_next = std::move(xy);
  }
  if (mc.zw_current_minus_next && !zw.empty()) {
    // Stored as current - next: the offset to the next frame is its negation.
    for (std::size_t p = 0; p < n; ++p) {
      zw.plane(0)[p] = static_cast<float>(-finite_or(zw.plane(0)[p], 0.0f) * sx);
      zw.plane(1)[p] = static_cast<float>(-finite_or(zw.plane(1)[p], 0.0f) * sy);
    }
    g->motion_next = std::move(zw);
  }
}

}  // namespace

void set_io_threads(int threads) {
  OIIO::attribute("threads", threads);
  OIIO::attribute("exr_threads", threads);
}

namespace {

std::string corners(const Box2i& b) {
  return "(" + std::to_string(b.x0) + "," + std::to_string(b.y0) + ")-(" +
         std::to_string(b.x1 - 1) + "," + std::to_string(b.y1 - 1) + ")";
}

// open_sequence; with `check_header_camera`, the first frame's header camera is checked against
// its position pass (not for a --context, whose cameras must be the input's).
SequenceInfo open_sequence(const InputOptions& options, bool check_header_camera);

// --context: the whole picture's frames, probed from the one matching `seq`'s first frame with
// the same reading options; its frames are `seq`'s. Throws Error(kInput) naming the context's
// file when its display window is not `seq`'s or its data window does not hold `seq`'s.
std::shared_ptr<const SequenceInfo> open_context(const SequenceInfo& seq,
                                                 const InputOptions& options) {
  InputOptions c = options;
  c.pattern = options.context;
  c.context.clear();
  c.frames = std::to_string(seq.frames.front());
  c.skip_missing = false;
  std::shared_ptr<SequenceInfo> context;
  try {
    context = std::make_shared<SequenceInfo>(open_sequence(c, false));
  } catch (const Error& e) {
    throw Error(e.kind(), e.file(),
                "--context: " + std::string(e.what()) + " (the input's first frame is " +
                    std::to_string(seq.frames.front()) + ")");
  }
  const std::string first = context->pattern.path_for(seq.frames.front());
  // The same shot's frames have the same passes.
  for (int r = 0; r < kRoleCount; ++r) {
    const Role role = static_cast<Role>(r);
    // Positions are read only to fit a camera, which the context's frames do on their own;
    // normals from depth need none.
    if (role == Role::kPosition || (role == Role::kNormal && seq.normals_from_depth)) continue;
    // A shot's own indirect light is never read (a guide's is).
    if (role == Role::kIndirect) continue;
    if (seq.layout.has(role) && !context->layout.has(role))
      throw_input(first, std::string("--context: has no ") + role_name(role) +
                             " channels, which the input has");
  }
  if (context->display_window != seq.display_window)
    throw_input(first, "--context: display window " + corners(context->display_window) +
                           " is not the input's " + corners(seq.display_window));
  const Box2i& cw = context->data_window;
  const Box2i& dw = seq.data_window;
  if (dw.x0 < cw.x0 || dw.y0 < cw.y0 || dw.x1 > cw.x1 || dw.y1 > cw.y1)
    throw_input(first, "--context: data window " + corners(cw) + " does not hold the input's " +
                           corners(dw));
  context->frames = seq.frames;
  return context;
}

// Warns once, naming the frames that `gaps` (of the input's frames on disk) lacks. The
// temporal stage takes its shot's gaps as ends, unless a context holds the frames.
void warn_about_gaps(const std::string& pattern, const FrameGaps& gaps, const SequenceInfo& seq) {
  const bool one_frame = gaps.gaps.size() == 1 && gaps.gaps[0].first == gaps.gaps[0].second;
  const bool filled = seq.context && find_frame_gaps(seq.frames_on_disk).gaps.empty();
  log_warning(pattern + ": " + (one_frame ? "frame " : "frames ") + frame_gaps_text(gaps) +
              (one_frame ? " is" : " are") + " missing; " +
              (filled ? std::string("the temporal stage reads the context's")
                      : std::string("the temporal stage ends the shot at ") +
                            (gaps.gaps.size() == 1 ? "the gap" : "each gap") +
                            ", as at its first and last frames"));
}

SequenceInfo open_sequence(const InputOptions& options, bool check_header_camera) {
  SequenceInfo seq;
  std::vector<int> frames_in_name;
  seq.pattern = parse_sequence_pattern(options.pattern, &frames_in_name);
  if (!seq.pattern.has_frame_field) {
    seq.pattern = pattern_for_single_file(options.pattern, &frames_in_name);
    if (!fs::exists(options.pattern)) throw_io(options.pattern, "no such file");
    // Digits without a leading zero (`shot.10000.exr`) fit any padding up to their count: take
    // the one under which the most files of the shot are found (#### for 9999, 10000, ...).
    const std::string digits = std::to_string(std::abs(frames_in_name.front()));
    if (seq.pattern.has_frame_field && seq.pattern.padding == static_cast<int>(digits.size())) {
      SequencePattern best = seq.pattern;
      std::size_t most = find_frames_on_disk(best).size();
      for (int padding = seq.pattern.padding - 1; padding >= 1; --padding) {
        SequencePattern candidate = seq.pattern;
        candidate.padding = padding;
        const std::size_t found = find_frames_on_disk(candidate).size();
        if (found > most) {
          most = found;
          best = candidate;
        }
      }
      seq.pattern = best;
    }
  }
  // The whole shot on disk, also for one named file of it (`shot.0005.exr`): the temporal
  // window reads its neighbours, so a frame has the same bits however the shot is split.
  seq.frames_on_disk =
      seq.pattern.has_frame_field ? find_frames_on_disk(seq.pattern) : std::vector<int>();
  std::vector<int> wanted;
  if (!options.frames.empty())
    wanted = parse_frame_list(options.frames);
  else if (!frames_in_name.empty())
    wanted = frames_in_name;
  else
    wanted = seq.frames_on_disk;
  // Frames found on disk rather than asked for: a gap among them is no error, but is said.
  const FrameGaps gaps = options.frames.empty() && frames_in_name.empty()
                             ? find_frame_gaps(seq.frames_on_disk)
                             : FrameGaps();
  if (wanted.empty()) throw_io(options.pattern, "no files match this pattern");
  if (seq.frames_on_disk.empty()) {
    for (int f : wanted)
      if (fs::exists(seq.pattern.path_for(f))) seq.frames_on_disk.push_back(f);
    std::sort(seq.frames_on_disk.begin(), seq.frames_on_disk.end());
  }
  for (int f : wanted) {
    if (std::binary_search(seq.frames_on_disk.begin(), seq.frames_on_disk.end(), f)) {
      seq.frames.push_back(f);
    } else if (options.skip_missing) {
      log_warning(seq.pattern.path_for(f) + ": frame " + std::to_string(f) +
                  " is missing; skipped");
    } else {
      throw_io(seq.pattern.path_for(f), "frame " + std::to_string(f) + " is missing");
    }
  }
  if (seq.frames.empty()) throw_io(options.pattern, "none of the requested frames exist");

  const std::string first = seq.pattern.path_for(seq.frames.front());
  auto in = open_exr(first);
  seq.channels = probe_channels(*in);
  const OIIO::ImageSpec& spec = in->spec();
  seq.display_window = display_window_of(spec);
  seq.data_window = data_window_of(spec);
  if (seq.data_window.empty()) throw_input(first, "data window is empty (zero pixels)");
  const Box2i& dw = seq.data_window;
  const Box2i& fw = seq.display_window;
  if (dw.x1 <= fw.x0 || dw.x0 >= fw.x1 || dw.y1 <= fw.y0 || dw.y0 >= fw.y1) {
    throw_input(first, "data window " + corners(dw) + " lies wholly outside the display window " +
                           corners(fw) + ": none of its pixels is in the picture");
  }
  for (int part = 0; in->seek_subimage(part, 0); ++part)
    seq.chunk_rows = std::max(seq.chunk_rows, detail::rows_per_chunk(in->spec()));
  in->geterror();  // seek_subimage past the last part leaves a message
  in->seek_subimage(0, 0);
  seq.pixel_aspect = in->spec().get_float_attribute("PixelAspectRatio", 1.0f);
  if (!(seq.pixel_aspect > 0) || !std::isfinite(seq.pixel_aspect)) seq.pixel_aspect = 1.0;
  seq.layout = resolve_layout(seq.channels, options.layout, options.channel_overrides, first);
  if (!options.depth_kind.empty() &&
      !parse_depth_kind(options.depth_kind, &seq.layout.preset.depth_kind))
    throw_usage("unknown --depth-kind '" + options.depth_kind +
                "' (planar, radial, inverse, negative)");
  if (!options.normal_space.empty() &&
      !parse_normal_space(options.normal_space, &seq.layout.preset.normal_space))
    throw_usage("unknown --normal-space '" + options.normal_space +
                "' (auto, world, camera, camera-gl)");
  if (!options.camera.sidecar.empty() && options.camera.hfov_deg > 0)
    throw_usage("--camera and --fov both give the camera: use one");
  if (!options.normals.empty() && options.normals != "auto" && options.normals != "pass" &&
      options.normals != "depth")
    throw_usage("unknown --normals '" + options.normals + "' (auto, pass, depth)");
  if (options.normals == "pass" && !seq.layout.has(Role::kNormal))
    throw_input(first,
                "has no normal channels (--normals pass; give --channel normal=NAME, or "
                "--normals depth)");
  seq.normals_from_depth =
      options.normals == "depth" || (options.normals != "pass" && !seq.layout.has(Role::kNormal));
  if (seq.layout.preset.normal_space == NormalSpace::kWorld && !seq.normals_from_depth) {
    try {
      if (!find_camera(seq, options, spec, seq.frames.front(), first, nullptr).has_world_transform)
        log_warning(first +
                    ": normals are in world space but the camera has no world transform "
                    "(--fov, or a sidecar without worldToCamera): they are taken as camera-space");
    } catch (const Error&) {
      // No camera in the header (fitted to the position pass, which gives a world transform)
      // or none at all: reading the frame reports it.
    }
  }
  if (!options.context.empty()) {
    seq.context = open_context(seq, options);
    // The temporal stage's neighbours are the whole shot's: a frame the region lacks is read
    // from the context alone.
    std::vector<int> both;
    std::set_union(seq.frames_on_disk.begin(), seq.frames_on_disk.end(),
                   seq.context->frames_on_disk.begin(), seq.context->frames_on_disk.end(),
                   std::back_inserter(both));
    seq.frames_on_disk = std::move(both);
  }
  if (check_header_camera) {
    check_header_camera_against_positions(seq, options, *in, first);
    check_depth_against_positions(seq, options, *in, first);
  }
  if (!gaps.gaps.empty()) warn_about_gaps(options.pattern, gaps, seq);
  return seq;
}

}  // namespace

SequenceInfo open_sequence(const InputOptions& options) {
  SequenceInfo seq = open_sequence(options, true);
  if (!options.views.empty()) seq.views = detail::open_views(seq, options);
  if (!options.guide.empty()) seq.guide = detail::open_guide(seq, options);
  return seq;
}

std::shared_ptr<const SequenceInfo> still_sequence(const GBuffer& frame) {
  const Box2i& window = frame.data_window;
  if (window.empty()) throw_usage("still_sequence: the frame's data window is empty");
  auto check = [&](const Image& pass, Role role, int channels) {
    if (pass.channels() == channels && pass.width() == window.width() &&
        pass.height() == window.height())
      return;
    throw_usage(std::string("still_sequence: the ") + role_name(role) + " pass must have " +
                std::to_string(channels) + " channel(s) of " + std::to_string(window.width()) +
                " x " + std::to_string(window.height()) + " (the data window), not " +
                std::to_string(pass.channels()) + " of " + std::to_string(pass.width()) + " x " +
                std::to_string(pass.height()));
  };
  auto seq = std::make_shared<SequenceInfo>();
  seq->layout.preset = *find_layout_preset("custom");
  seq->layout.preset.direct_includes_albedo = true;  // GBuffer::direct is the reflected light
  seq->layout.detected_because = "a frame given as buffers";
  auto provide = [&](const Image& pass, Role role, int channels) {
    check(pass, role, channels);
    seq->layout.roles[static_cast<int>(role)] = {{0, role_name(role)}};
  };
  provide(frame.depth, Role::kDepth, 1);
  provide(frame.normal, Role::kNormal, 3);
  provide(frame.albedo, Role::kAlbedo, 3);
  provide(frame.direct, Role::kDirect, 3);
  if (!frame.emission.empty()) provide(frame.emission, Role::kEmission, 3);
  if (!frame.beauty.empty()) provide(frame.beauty, Role::kBeauty, 4);
  seq->pattern.prefix = frame.path;
  seq->frames = seq->frames_on_disk = {frame.frame};
  seq->display_window = frame.display_window;
  seq->data_window = window;
  return seq;
}

namespace detail {

std::unique_ptr<OIIO::ImageInput> open_input_exr(const std::string& path) { return open_exr(path); }

SequenceInfo open_view_sequence(const InputOptions& options) {
  InputOptions own = options;
  own.views.clear();
  own.context.clear();
  return open_sequence(own, false);
}

}  // namespace detail

Camera read_camera(const SequenceInfo& seq, int frame, const InputOptions& options) {
  const std::string path = seq.pattern.path_for(frame);
  auto in = open_exr(path);
  const FillChannels fill = [&](int subimage, const std::vector<detail::PlaneTarget>& targets) {
    detail::read_float_channels(*in, subimage, targets, seq.data_window, path);
  };
  const FrameChannels channels{seq.channels.channels, fill};
  return find_camera(seq, options, in->spec(), frame, path, &channels);
}

namespace {

// The space `g`'s normal pass is read in: the layout's or --normal-space's, or for auto the one
// that agrees with the normals `g`'s depth (converted already) implies. Sets g.normals_source
// and, with `report`, warns when the space is doubtful or contradicts the depth.
NormalSpace normal_space_of(const SequenceInfo& seq, const InputOptions& options, GBuffer& g,
                            bool report) {
  const LayoutPreset& preset = seq.layout.preset;
  const std::string said_by =
      options.normal_space.empty() ? "the " + preset.name + " layout says" : "--normal-space says";
  detail::NormalSpaceScores scores;
  // A lat-long view's normals are not checked against its depth (the scores take a pinhole).
  if (!g.depth.empty() && g.camera.projection == Projection::kPinhole)
    scores =
        detail::score_normal_spaces(g.normal, g.depth, g.camera, g.display_window, g.data_window);
  const detail::NormalSpaceChoice choice = detail::choose_normal_space(
      preset.normal_space, scores, g.camera.has_world_transform, said_by);
  g.normals_source = pass_name(seq, Role::kNormal) + " in " + normal_space_name(choice.space) +
                     " space, " + choice.reason;
  if (report) log_info(g.path + ": normals " + g.normals_source);
  if (report && !choice.warning.empty()) log_warning(g.path + ": " + choice.warning);
  return choice.space;
}

// The G-buffer of `roles` from `input`'s headers, its planes filled by `fill` (from the file or
// from the kept pixels) and converted to the library's conventions. With `report`, what the
// conversion found wrong with the frame is warned about.
GBuffer convert_gbuffer(const SequenceInfo& seq, int frame, RoleMask roles,
                        const InputOptions& options, const ColorManagement* color,
                        const detail::DecodedInput& input, const FillChannels& fill, bool report) {
  const std::string& path = input.path;
  assert(!input.parts.empty());
  const OIIO::ImageSpec& spec = input.parts.front().spec;
  check_windows(seq, spec, path);

  GBuffer g;
  g.path = path;
  g.frame = frame;
  g.display_window = seq.display_window;
  g.data_window = seq.data_window;
  std::vector<std::vector<std::string>> channel_names;
  for (const detail::DecodedInput::Part& part : input.parts)
    channel_names.push_back(part.spec.channelnames);
  const FrameChannels frame_channels{channel_names, fill};
  g.camera = find_camera(seq, options, spec, frame, path, &frame_channels);
  if (report) log_info(path + ": camera from " + g.camera.source);
  const int w = g.width(), h = g.height();

  // Each role's planes, allocated once and read into straight from the file's strips (no
  // whole-frame copy besides the G-buffer itself); converted in place afterwards.
  const LayoutPreset& preset = seq.layout.preset;
  auto wanted = [&](Role role) { return (roles & role_bit(role)) && seq.layout.has(role); };
  if ((roles & role_bit(Role::kDepth)) && !seq.layout.has(Role::kDepth))
    throw_input(path, "has no depth channel");
  const bool read_normals = (roles & role_bit(Role::kNormal)) && !seq.normals_from_depth;
  if (read_normals && !seq.layout.has(Role::kNormal)) throw_input(path, "has no normal channels");
  const auto channels = [&](Role role) {
    return static_cast<int>(seq.layout.channels(role).size());
  };
  Image motion_xy, motion_zw;
  NamedPlanes by_subimage;
  const auto target = [&](Role role, Image* image, int first, int count) {
    const std::vector<ChannelRef>& refs = seq.layout.channels(role);
    for (int c = 0; c < count; ++c)
      by_subimage[refs[first + c].subimage].emplace_back(refs[first + c].name, image->plane(c));
  };
  if (roles & role_bit(Role::kDepth)) {
    g.depth = Image(w, h, 1);
    target(Role::kDepth, &g.depth, 0, 1);
  }
  if (read_normals) {
    g.normal = Image(w, h, channels(Role::kNormal));
    target(Role::kNormal, &g.normal, 0, g.normal.channels());
  }
  for (auto [role, image] : {std::pair{Role::kAlbedo, &g.albedo},
                             {Role::kDirect, &g.direct},
                             {Role::kEmission, &g.emission},
                             {Role::kIndirect, &g.indirect}}) {
    if (!wanted(role)) continue;
    *image = Image(w, h, channels(role));
    target(role, image, 0, image->channels());
  }
  if (wanted(Role::kMotion)) {
    const int n = channels(Role::kMotion);
    motion_xy = Image(w, h, std::min(n, 2));
    target(Role::kMotion, &motion_xy, 0, motion_xy.channels());
    if (n >= 4) {
      motion_zw = Image(w, h, 2);
      target(Role::kMotion, &motion_zw, 2, 2);
    }
  }
  if (wanted(Role::kBeauty)) {
    // A beauty without alpha is opaque.
    const int n = channels(Role::kBeauty);
    g.beauty = Image(w, h, n < 4 ? n + 1 : n);
    if (n < 4) std::fill_n(g.beauty.plane(n), g.beauty.plane_size(), 1.0f);
    target(Role::kBeauty, &g.beauty, 0, n);
  }
  fill_named_planes(by_subimage, frame_channels, path);

  std::size_t non_finite = 0;
  if (roles & role_bit(Role::kDepth)) {
    const DepthCounts counts = convert_depth(g.depth, preset.depth_kind, preset.background_depth,
                                             g.camera, g.display_window, g.data_window);
    if (report) warn_if_no_surfaces(counts, g.depth.plane_size(), preset.depth_kind, path);
  }
  if ((roles & role_bit(Role::kNormal)) && seq.normals_from_depth) {
    if (g.camera.projection != Projection::kPinhole)
      throw_input(path, "has no normal channels, which a lat-long view needs");
    g.normal = detail::normals_from_depth(g.depth, g.camera, g.display_window, g.data_window);
  } else if (read_normals) {
    non_finite += sanitize(&g.normal);
    const NormalSpace space = normal_space_of(seq, options, g, report);
    convert_normals(g.normal, g.depth, space, g.camera, g.display_window, g.data_window);
  }
  // Light and albedo into the working space as they are read; depth, normals and motion are
  // data and stay as they are.
  const auto colour_pass = [&](Image* image) {
    non_finite += sanitize(image);
    if (color && image->channels() >= 3) color->input_to_working(image);
  };
  if (wanted(Role::kAlbedo)) colour_pass(&g.albedo);
  if (wanted(Role::kDirect)) {
    colour_pass(&g.direct);
    if (!preset.direct_includes_albedo) {
      if (g.albedo.empty()) throw_input(path, "direct light excludes albedo but there is none");
      for (int c = 0; c < 3; ++c)
        for (std::size_t p = 0; p < g.direct.plane_size(); ++p)
          g.direct.plane(c)[p] = finite_or(g.direct.plane(c)[p] * g.albedo.plane(c)[p], 0.0f);
    }
  }
  if (wanted(Role::kEmission)) colour_pass(&g.emission);
  if (wanted(Role::kIndirect)) {
    colour_pass(&g.indirect);
    if (preset.direct_includes_albedo) {
      if (g.albedo.empty())
        throw_input(path, "indirect light includes albedo but there is no albedo to divide by");
      for (int c = 0; c < 3; ++c)
        for (std::size_t p = 0; p < g.indirect.plane_size(); ++p) {
          const float a = g.albedo.plane(c)[p];
          g.indirect.plane(c)[p] = a > 0 ? finite_or(g.indirect.plane(c)[p] / a, 0.0f) : 0.0f;
        }
    }
  }
  if (wanted(Role::kMotion))
    convert_motion(std::move(motion_xy), std::move(motion_zw), preset.motion, g.display_window, &g);
  if (wanted(Role::kBeauty)) {
    non_finite += sanitize(&g.beauty);
    if (color) color->input_to_working(&g.beauty);  // R, G, B; alpha is coverage
  }
  g.sanitized = non_finite;
  if (non_finite > 0 && report)
    log_warning(path + ": " + std::to_string(non_finite) +
                " NaN or infinite values in normal, albedo, light or beauty channels read as 0");
  return g;
}

// `region`'s passes pasted into those of `context` (the same frame of the whole picture), which
// cover the context's data window: the region's own pixels where it has them, the context's
// around them. Normals from depth are derived again over the whole, so that the region's edge
// takes its neighbours outside. The region's path, camera and counts stay.
GBuffer embed_in_context(const SequenceInfo& seq, GBuffer region, GBuffer context) {
  const std::string& path = context.path;
  // The same frame of the same shot sees through the same camera (to float precision, as
  // headers written by two renders of it may round differently).
  const auto near = [](double a, double b) {
    return std::fabs(a - b) <= 1e-4 * (1 + std::fabs(a));
  };
  const Camera &a = region.camera, &b = context.camera;
  bool same = near(a.fx, b.fx) && near(a.fy, b.fy) && near(a.cx, b.cx) && near(a.cy, b.cy) &&
              a.has_world_transform == b.has_world_transform;
  for (int i = 0; i < 4 && same; ++i)
    for (int j = 0; j < 4; ++j)
      same = same && near(a.world_to_camera[i][j], b.world_to_camera[i][j]);
  if (!same)
    throw_input(path, "--context: its camera is not the input's frame " +
                          std::to_string(region.frame) + " camera (not the same shot and frame?)");
  const auto paste = [&](Image& from, Image& into, const char* what) {
    if (from.empty()) {
      into = Image();
      return;
    }
    if (into.channels() != from.channels())
      throw_input(path, std::string("--context: its ") + what + " has " +
                            std::to_string(into.channels()) + " channels, the input's " +
                            std::to_string(from.channels()));
    detail::copy_window(from, region.data_window, &into, context.data_window);
    from = Image();
  };
  paste(region.depth, context.depth, "depth");
  if (seq.normals_from_depth && !region.normal.empty()) {
    region.normal = Image();
    context.normal = detail::normals_from_depth(context.depth, region.camera,
                                                context.display_window, context.data_window);
  } else {
    paste(region.normal, context.normal, "normal");
  }
  paste(region.albedo, context.albedo, "albedo");
  paste(region.direct, context.direct, "direct light");
  paste(region.emission, context.emission, "emission");
  paste(region.motion_prev, context.motion_prev, "motion");
  paste(region.motion_next, context.motion_next, "motion");
  paste(region.beauty, context.beauty, "beauty");
  // The frame is the region's, over the context's window.
  context.path = std::move(region.path);
  context.camera = std::move(region.camera);
  context.sanitized = region.sanitized;
  return context;
}

// With --context, `g` embedded in its frame of the whole picture.
GBuffer with_context(const SequenceInfo& seq, int frame, RoleMask roles,
                     const InputOptions& options, const ColorManagement* color, GBuffer g,
                     bool report) {
  if (!seq.context) return g;
  GBuffer context = detail::read_input_frame(*seq.context, frame, roles, options, color, report).g;
  return embed_in_context(seq, std::move(g), std::move(context));
}

}  // namespace

namespace detail {

InputFrame read_input_frame(const SequenceInfo& seq, int frame, RoleMask roles,
                            const InputOptions& options, const ColorManagement* color,
                            bool report) {
  const std::string path = seq.pattern.path_for(frame);
  // A neighbour of the temporal stage that only the context has: its whole picture. (A frame
  // to write is the region's: its file missing now is an error below.)
  if (seq.context && std::find(seq.frames.begin(), seq.frames.end(), frame) == seq.frames.end() &&
      !fs::exists(path))
    return read_input_frame(*seq.context, frame, roles, options, color, report);
  auto in = open_exr(path);
  auto input = std::make_shared<DecodedInput>(decode_input(*in, path));
  const FillChannels fill = [&](int subimage, const std::vector<PlaneTarget>& targets) {
    read_float_channels(*in, subimage, targets, seq.data_window, path);
  };
  GBuffer g = convert_gbuffer(seq, frame, roles, options, color, *input, fill, report);
  in.reset();
  g = with_context(seq, frame, roles, options, color, std::move(g), report);
  return {std::move(g), std::move(input), {}, {}};
}

}  // namespace detail

GBuffer read_gbuffer(const SequenceInfo& seq, int frame, RoleMask roles,
                     const InputOptions& options, const ColorManagement* color) {
  return detail::read_input_frame(seq, frame, roles, options, color, true).g;
}

}  // namespace ssgi
