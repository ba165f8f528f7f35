// Cameras from EXR header attributes (OpenEXR standard, Nuke, V-Ray, Arnold, Redshift, Unreal)
// and from JSON sidecar files.
#include "io/camera_header.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "io/camera.h"
#include "throw.h"

namespace ssgi::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

Imath::M44d diagonal(double x, double y, double z) {
  Imath::M44d d;
  d[0][0] = x;
  d[1][1] = y;
  d[2][2] = z;
  return d;
}

// Exact-case lookup: OIIO keeps EXR attribute names as written, except for a few it renames to
// its own (lower-case) conventions, and those renamed names mean something else (see below).
const OIIO::ParamValue* find_exact(const OIIO::ImageSpec& spec, const std::string& name) {
  return spec.find_attribute(name, OIIO::TypeDesc::UNKNOWN, /*casesensitive=*/true);
}

// `name`, or Nuke's "exr/<name>": Nuke prefixes the EXR attributes it read, and files written
// from Nuke metadata can carry that prefix.
const OIIO::ParamValue* find_attr(const OIIO::ImageSpec& spec, const std::string& name) {
  if (const OIIO::ParamValue* p = find_exact(spec, name)) return p;
  return find_exact(spec, "exr/" + name);
}

// All numbers of a numeric attribute (float or double, any aggregate) or of a string holding
// numbers separated by commas or blanks, as a metadata pass-through may write them.
std::vector<double> numbers_of(const OIIO::ParamValue& p) {
  std::vector<double> out;
  const OIIO::TypeDesc t = p.type();
  const std::size_t n = t.basevalues() * static_cast<std::size_t>(p.nvalues());
  if (t.basetype == OIIO::TypeDesc::FLOAT) {
    const float* v = static_cast<const float*>(p.data());
    out.assign(v, v + n);
  } else if (t.basetype == OIIO::TypeDesc::DOUBLE) {
    const double* v = static_cast<const double*>(p.data());
    out.assign(v, v + n);
  } else if (t.basetype == OIIO::TypeDesc::INT) {
    const int* v = static_cast<const int*>(p.data());
    out.assign(v, v + n);
  } else if (t.basetype == OIIO::TypeDesc::UINT) {
    const unsigned* v = static_cast<const unsigned*>(p.data());
    out.assign(v, v + n);
  } else if (t == OIIO::TypeDesc::STRING) {
    std::string s = p.get_string(0);
    for (char& c : s)
      if (c == ',' || c == '[' || c == ']' || c == '(' || c == ')') c = ' ';
    std::istringstream is(s);
    double v;
    while (is >> v) out.push_back(v);
    if (!is.eof()) out.clear();
  }
  return out;
}

std::optional<Imath::M44d> matrix_attr(const OIIO::ImageSpec& spec, const std::string& name,
                                       const std::string& file) {
  const OIIO::ParamValue* p = find_attr(spec, name);
  if (!p) return std::nullopt;
  const std::vector<double> v = numbers_of(*p);
  if (v.size() != 16)
    throw_input(file, "header attribute " + std::string(p->name()) + " is not a 4x4 matrix");
  Imath::M44d m;
  for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = v[i];
  return m;
}

std::optional<double> number_attr(const OIIO::ImageSpec& spec, const std::string& name) {
  const OIIO::ParamValue* p = find_attr(spec, name);
  if (!p) return std::nullopt;
  const std::vector<double> v = numbers_of(*p);
  if (v.size() != 1 || !std::isfinite(v[0])) return std::nullopt;
  return v[0];
}

double pixel_aspect_of(const OIIO::ImageSpec& spec) {
  // OIIO renames pixelAspectRatio to PixelAspectRatio; accept either.
  std::optional<double> pa = number_attr(spec, "PixelAspectRatio");
  if (!pa) pa = number_attr(spec, "pixelAspectRatio");
  return pa && *pa > 0 ? *pa : 1.0;
}

// OpenEXR's screen window (Technical Introduction, "Projection, camera coordinate system and
// screen window"): centre C and width W on the z = 1 plane; its height follows from the display
// window and the pixel aspect ratio, and it covers the display window. Screen y points up, NDC
// y down, so the window maps to NDC [0,1]^2 as RenderMan maps its screen window to NDC.
Imath::M44d screen_to_ndc(const OIIO::ImageSpec& spec, const Box2i& display,
                          const std::string& file) {
  double cx = 0, cy = 0, width = 1;
  if (const OIIO::ParamValue* p = find_attr(spec, "screenWindowCenter")) {
    const std::vector<double> v = numbers_of(*p);
    if (v.size() != 2) throw_input(file, "screenWindowCenter is not two numbers");
    cx = v[0];
    cy = v[1];
  }
  if (std::optional<double> w = number_attr(spec, "screenWindowWidth")) width = *w;
  if (!(width > 0 && std::isfinite(width) && std::isfinite(cx) && std::isfinite(cy)))
    throw_input(file, "screenWindowCenter/screenWindowWidth do not define a screen window");
  const double height =
      width * display.height() / (static_cast<double>(display.width()) * pixel_aspect_of(spec));
  Imath::M44d s;
  s[0][0] = 1 / width;
  s[1][1] = -1 / height;
  s[3][0] = 0.5 - cx / width;
  s[3][1] = 0.5 + cy / height;
  return s;
}

Camera from_matrices(const Imath::M44d& world_to_camera, const Imath::M44d& world_to_ndc,
                     const Box2i& display, const std::string& file, const std::string& source) {
  Camera c = camera_from_matrices(world_to_camera, world_to_ndc, display, file);
  c.source = "header " + source;
  return c;
}

// A camera from a horizontal field of view and, when known, a world-to-camera transform whose
// camera frame is mapped to ours by `local_to_ours` (a signed permutation).
Camera from_fov(double hfov_deg, const std::optional<Imath::M44d>& world_to_local,
                const Imath::M44d& local_to_ours, const OIIO::ImageSpec& spec, const Box2i& display,
                const std::string& file, const std::string& source) {
  if (!(hfov_deg > 0 && hfov_deg < 180))
    throw_input(file, source + ": field of view " + std::to_string(hfov_deg) +
                          " degrees is outside (0, 180)");
  Camera c = camera_from_fov(hfov_deg, display, pixel_aspect_of(spec));
  if (world_to_local) {
    c.world_to_camera = *world_to_local * local_to_ours;
    try {
      inverse_checked(c.world_to_camera);  // the normal transform needs it
    } catch (const Error& e) {
      throw_input(file, source + ": " + e.what());
    }
    c.has_world_transform = true;
  }
  c.source = "header " + source;
  return c;
}

// V-Ray writes cameraTransform (camera-to-world), cameraFov (horizontal, degrees: 73.72 for a
// 24 mm lens on a 36 mm aperture in the header dumps ProEXR users post), cameraFocalLength and
// cameraAperture (mm), and cameraProjection (0 in every perspective render seen). OIIO renames
// cameraTransform to "worldtocamera" (exrinput.cpp, exr_tag_to_oiio_std) although it is
// camera-to-world. Its local frame is inferred, not documented: the V-Ray App SDK gives
// +Y up, -Z forward for an identity transform, which 3ds Max headers match (world Z up); in
// V-Ray for Maya headers the matrix's -Z is world up (Y) and -Y is forward, which is also what
// published Nuke "camera from V-Ray EXR" scripts undo. Without a sidecar, that is our best
// reading; the source string names it so a wrong camera can be traced.
std::optional<Camera> vray_camera(const OIIO::ImageSpec& spec, const Box2i& display,
                                  const std::string& file) {
  std::optional<double> fov = number_attr(spec, "cameraFov");
  if (!fov) {
    // Focal length over aperture gives the film-back fov, which differs from the rendered fov
    // when the host fits the film gate to another aspect; only a fallback.
    const std::optional<double> focal = number_attr(spec, "cameraFocalLength");
    const std::optional<double> aperture = number_attr(spec, "cameraAperture");
    if (focal && aperture && *focal > 0 && *aperture > 0)
      fov = 2 * std::atan(0.5 * *aperture / *focal) * 180 / kPi;
  }
  if (!fov) return std::nullopt;
  if (std::optional<double> projection = number_attr(spec, "cameraProjection");
      projection && *projection != 0)
    throw_input(file, "V-Ray cameraProjection " + std::to_string(static_cast<int>(*projection)) +
                          " is not a perspective camera; give --fov or --camera");
  std::optional<Imath::M44d> transform = matrix_attr(spec, "cameraTransform", file);
  if (!transform) transform = matrix_attr(spec, "worldtocamera", file);
  std::optional<Imath::M44d> world_to_local;
  if (transform) {
    // Written both ways in the wild: translation in the last row (Imath) or last column.
    Imath::M44d t = *transform;
    const double last_col = std::abs(t[0][3]) + std::abs(t[1][3]) + std::abs(t[2][3]);
    const double last_row = std::abs(t[3][0]) + std::abs(t[3][1]) + std::abs(t[3][2]);
    if (last_col > 0 && last_row == 0) t = t.transposed();
    try {
      world_to_local = inverse_checked(t);
    } catch (const Error& e) {
      throw_input(file, std::string("V-Ray cameraTransform: ") + e.what());
    }
  }
  bool maya = false;
  if (const OIIO::ParamValue* p = find_attr(spec, "vrayInfo/vrayversion"))
    maya = p->get_string(0).find("Maya") != std::string::npos;
  Imath::M44d local_to_ours = diagonal(1, 1, -1);  // +Y up, -Z forward
  if (maya) {
    local_to_ours = Imath::M44d();
    local_to_ours[1][1] = 0;
    local_to_ours[2][2] = 0;
    local_to_ours[1][2] = -1;  // local -Y is our +z (forward)
    local_to_ours[2][1] = -1;  // local -Z is our +y (up)
  }
  return from_fov(*fov, world_to_local, local_to_ours, spec, display, file,
                  transform ? "V-Ray cameraTransform/cameraFov" : "V-Ray cameraFov");
}

// Arnold EXRs rendered from Maya (MtoA) carry CameraFov, CameraFocalLength and
// CameraFilmApertureHorizontal/Vertical beside worldToCamera, but no projection matrix. The
// names are documented only by the Nuke tools that rebuild cameras from them (e.g. MrLixm's
// metadataToCamera), not by Autodesk: those read focal length and aperture in one unit and
// negate worldToCamera's z, Arnold cameras looking down -Z. We do the same.
std::optional<Camera> arnold_camera(const OIIO::ImageSpec& spec, const Box2i& display,
                                    const std::string& file) {
  std::optional<double> fov = number_attr(spec, "CameraFov");
  if (!fov) {
    const std::optional<double> focal = number_attr(spec, "CameraFocalLength");
    const std::optional<double> aperture = number_attr(spec, "CameraFilmApertureHorizontal");
    if (focal && aperture && *focal > 0 && *aperture > 0)
      fov = 2 * std::atan(0.5 * *aperture / *focal) * 180 / kPi;
  }
  if (!fov) return std::nullopt;
  std::optional<Imath::M44d> world_to_camera = matrix_attr(spec, "worldToCamera", file);
  // OIIO before 2.2 renamed worldToCamera to "worldtocamera".
  if (!world_to_camera) world_to_camera = matrix_attr(spec, "worldtocamera", file);
  return from_fov(*fov, world_to_camera, diagonal(1, 1, -1), spec, display, file,
                  world_to_camera ? "Arnold worldToCamera/CameraFov" : "Arnold CameraFov");
}

// Redshift (from 2.6.04 and 2.5.64; Maxon, "EXR Metadata") writes rs/camera/transform, the
// camera-to-world matrix with its translation in the last row as Imath stores it (Nuke tools
// that rebuild the camera read elements 12 to 14 as the position; a string of 16 numbers in some
// files), rs/camera/fov ("the fov in radians" by Maxon's page; some tools read degrees, so a
// value above pi is taken as degrees), rs/camera/aperture, rs/camera/shift and rs/camera/aspect;
// builds before those wrote RSCameraTransform and RSCameraFOV. The camera's local axes are
// +Y up, +Z forward (the Nuke tools flip Z to turn it into Nuke's camera, which looks down -Z).
// A lens shift has no documented unit: a camera with one is not read from the header (the
// position pass, when there is one, gives it).
std::optional<Camera> redshift_camera(const OIIO::ImageSpec& spec, const Box2i& display,
                                      const std::string& file) {
  std::optional<double> fov = number_attr(spec, "rs/camera/fov");
  if (!fov) fov = number_attr(spec, "RSCameraFOV");
  if (!fov) return std::nullopt;
  if (const OIIO::ParamValue* p = find_attr(spec, "rs/camera/shift")) {
    for (double v : numbers_of(*p))
      if (v != 0) return std::nullopt;
  }
  const double degrees = *fov > kPi ? *fov : *fov * 180 / kPi;
  std::optional<Imath::M44d> transform = matrix_attr(spec, "rs/camera/transform", file);
  if (!transform) transform = matrix_attr(spec, "RSCameraTransform", file);
  std::optional<Imath::M44d> world_to_local;
  if (transform) {
    try {
      world_to_local = inverse_checked(*transform);
    } catch (const Error& e) {
      throw_input(file, std::string("Redshift rs/camera/transform: ") + e.what());
    }
  }
  return from_fov(degrees, world_to_local, Imath::M44d(), spec, display, file,
                  transform ? "Redshift rs/camera/transform/fov" : "Redshift rs/camera/fov");
}

// Unreal Engine's Movie Render Queue writes the camera as strings (MoviePipeline source,
// GetMetadataFromCameraLocRot and the image passes): unreal/camera/curPos/x, y, z in
// centimetres, unreal/camera/curRot/pitch, yaw, roll in degrees, and per render pass
// unreal/camera/<pass>/fov, the full horizontal angle in degrees (overscan included);
// <pass> is FinalImage for the deferred renderer. Unreal's world is left-handed, X forward,
// Y right, Z up; a rotator turns by roll about X, then pitch about Y, then yaw about Z
// (FRotationMatrix), and its view space is Y right, Z up, X forward: the library's camera space
// with the axes renamed.
std::optional<Camera> unreal_camera(const OIIO::ImageSpec& spec, const Box2i& display,
                                    const std::string& file) {
  std::optional<double> fov = number_attr(spec, "unreal/camera/FinalImage/fov");
  std::string fov_name = "unreal/camera/FinalImage/fov";
  if (!fov) {
    for (const OIIO::ParamValue& p : spec.extra_attribs) {
      const std::string name = p.name().string();
      if (name.rfind("unreal/camera/", 0) == 0 && name.size() > 4 &&
          name.compare(name.size() - 4, 4, "/fov") == 0) {
        fov = number_attr(spec, name);
        fov_name = name;
        if (fov) break;
      }
    }
  }
  if (!fov) return std::nullopt;
  const char* kPosition[] = {"unreal/camera/curPos/x", "unreal/camera/curPos/y",
                             "unreal/camera/curPos/z"};
  const char* kRotation[] = {"unreal/camera/curRot/pitch", "unreal/camera/curRot/yaw",
                             "unreal/camera/curRot/roll"};
  double position[3], rotation[3];
  bool posed = true;
  for (int i = 0; i < 3; ++i) {
    const std::optional<double> p = number_attr(spec, kPosition[i]);
    const std::optional<double> r = number_attr(spec, kRotation[i]);
    posed = posed && p && r;
    position[i] = p.value_or(0);
    rotation[i] = r.value_or(0);
  }
  std::optional<Imath::M44d> world_to_camera;
  if (posed) {
    const double d = kPi / 180;
    const double sp = std::sin(rotation[0] * d), cp = std::cos(rotation[0] * d);
    const double sy = std::sin(rotation[1] * d), cy = std::cos(rotation[1] * d);
    const double sr = std::sin(rotation[2] * d), cr = std::cos(rotation[2] * d);
    // FRotationMatrix's rows: the local X (forward), Y (right) and Z (up) axes in world space.
    const Imath::V3d forward(cp * cy, cp * sy, sp);
    const Imath::V3d right(sr * sp * cy - cr * sy, sr * sp * sy + cr * cy, -sr * cp);
    const Imath::V3d up(-(cr * sp * cy + sr * sy), cy * sr - cr * sp * sy, cr * cp);
    Imath::M44d camera_to_world;  // rows: our x (right), y (up), z (forward), position
    for (int j = 0; j < 3; ++j) {
      camera_to_world[0][j] = right[j];
      camera_to_world[1][j] = up[j];
      camera_to_world[2][j] = forward[j];
      camera_to_world[3][j] = position[j];
    }
    world_to_camera = inverse_checked(camera_to_world);
  }
  return from_fov(
      *fov, world_to_camera, Imath::M44d(), spec, display, file,
      posed ? "Unreal unreal/camera/curPos/curRot/" + fov_name.substr(14) : "Unreal " + fov_name);
}

using nlohmann::json;

Imath::M44d json_matrix(const json& j, const char* key, const std::string& file, int frame) {
  const std::string where = "frame " + std::to_string(frame) + ": \"" + key + "\"";
  std::vector<double> v;
  if (!j.is_array()) throw_input(file, where + " is not an array");
  for (const json& e : j) {
    if (e.is_array()) {
      for (const json& x : e) {
        if (!x.is_number()) throw_input(file, where + " has a non-number");
        v.push_back(x.get<double>());
      }
    } else if (e.is_number()) {
      v.push_back(e.get<double>());
    } else {
      throw_input(file, where + " has a non-number");
    }
  }
  if (v.size() != 16) throw_input(file, where + " does not hold 16 numbers");
  Imath::M44d m;
  for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = v[i];
  return m;
}

// The camera an object with the keys of the format (see camera_header.h) describes, or
// nullopt when it has none of them.
std::optional<Camera> json_camera(const json& j, const Box2i& display, const std::string& file,
                                  int frame) {
  const std::string source = "sidecar " + file;
  const std::string where = "frame " + std::to_string(frame);
  const bool has_w2c = j.contains("worldToCamera"), has_ndc = j.contains("worldToNDC");
  if (has_w2c && has_ndc) {
    const Imath::M44d w2c = json_matrix(j["worldToCamera"], "worldToCamera", file, frame);
    const Imath::M44d ndc = json_matrix(j["worldToNDC"], "worldToNDC", file, frame);
    Camera c = camera_from_matrices(w2c, ndc, display, file);
    c.source = source;
    return c;
  }
  if (!j.contains("hfov_deg")) {
    if (has_w2c || has_ndc)
      throw_input(file, where + ": worldToCamera and worldToNDC come together (or give hfov_deg)");
    return std::nullopt;
  }
  const json& fov = j["hfov_deg"];
  if (!fov.is_number() || !(fov.get<double>() > 0 && fov.get<double>() < 180))
    throw_input(file, where + ": \"hfov_deg\" is not a number in (0, 180)");
  double pixel_aspect = 1;
  if (j.contains("pixel_aspect")) {
    const json& pa = j["pixel_aspect"];
    if (!pa.is_number() || !(pa.get<double>() > 0))
      throw_input(file, where + ": \"pixel_aspect\" is not a positive number");
    pixel_aspect = pa.get<double>();
  }
  Camera c = camera_from_fov(fov.get<double>(), display, pixel_aspect);
  if (has_w2c) {
    c.world_to_camera = json_matrix(j["worldToCamera"], "worldToCamera", file, frame);
    try {
      inverse_checked(c.world_to_camera);
    } catch (const Error& e) {
      throw_input(file, where + ": worldToCamera: " + e.what());
    }
    c.has_world_transform = true;
  }
  c.source = source;
  return c;
}

}  // namespace

std::optional<Camera> camera_from_header(const OIIO::ImageSpec& spec, const Box2i& display_window,
                                         const std::string& file) {
  // OpenEXR standard attributes (Standard Attributes, "worldToCamera", "worldToNDC"); the
  // "exr/" prefix is Nuke's. OIIO before 2.2 read them as "worldtocamera" and "worldtoscreen"
  // (OIIO pull request #2609 stopped renaming worldToNDC), so that pair means the same.
  if (std::optional<Imath::M44d> w2c = matrix_attr(spec, "worldToCamera", file)) {
    if (std::optional<Imath::M44d> ndc = matrix_attr(spec, "worldToNDC", file))
      return from_matrices(*w2c, *ndc, display_window, file, "worldToCamera/worldToNDC");
    // RenderMan-style screen space: the OpenEXR screen window maps it onto the display window.
    if (std::optional<Imath::M44d> screen = matrix_attr(spec, "worldToScreen", file))
      return from_matrices(*w2c, *screen * screen_to_ndc(spec, display_window, file),
                           display_window, file, "worldToCamera/worldToScreen");
  }
  if (find_exact(spec, "worldtocamera") && find_exact(spec, "worldtoscreen")) {
    return from_matrices(*matrix_attr(spec, "worldtocamera", file),
                         *matrix_attr(spec, "worldtoscreen", file), display_window, file,
                         "worldToCamera/worldToNDC");
  }
  if (std::optional<Camera> c = vray_camera(spec, display_window, file)) return c;
  if (std::optional<Camera> c = arnold_camera(spec, display_window, file)) return c;
  if (std::optional<Camera> c = redshift_camera(spec, display_window, file)) return c;
  if (std::optional<Camera> c = unreal_camera(spec, display_window, file)) return c;
  return std::nullopt;
}

std::optional<Camera> latlong_camera_from_header(const OIIO::ImageSpec& spec,
                                                 const Box2i& display_window,
                                                 const std::string& file) {
  std::optional<Imath::M44d> w2c = matrix_attr(spec, "worldToCamera", file);
  if (!w2c && find_exact(spec, "worldtocamera")) w2c = matrix_attr(spec, "worldtocamera", file);
  if (!w2c) return std::nullopt;
  return latlong_camera(*w2c, display_window, file);
}

namespace {

// The sidecar's document, read and parsed once per file (and again only if the file changes):
// every frame of a shot asks for its camera, and parsing the whole file each time made a shot
// of N frames cost N^2. Errors are not kept: each call reports them again.
std::shared_ptr<const json> sidecar_document(const std::string& json_path) {
  struct Entry {
    std::filesystem::file_time_type time;
    std::uintmax_t size;
    std::shared_ptr<const json> document;
  };
  static std::mutex mutex;
  static std::map<std::string, Entry> cache;
  std::error_code ec;
  const auto time = std::filesystem::last_write_time(json_path, ec);
  const std::uintmax_t size = ec ? 0 : std::filesystem::file_size(json_path, ec);
  const bool known = !ec;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto it = cache.find(json_path);
    if (known && it != cache.end() && it->second.time == time && it->second.size == size)
      return it->second.document;
  }
  std::ifstream in(json_path, std::ios::binary);
  if (!in) throw_io(json_path, "cannot open camera file");
  auto root = std::make_shared<json>();
  try {
    *root = json::parse(in);
  } catch (const json::parse_error& e) {
    if (in.bad()) throw_io(json_path, "cannot read camera file");
    throw_input(json_path, std::string("not valid JSON: ") + e.what());
  }
  if (!root->is_object()) throw_input(json_path, "not a JSON object");
  if (known) {
    const std::lock_guard<std::mutex> lock(mutex);
    cache[json_path] = {time, size, root};
  }
  return root;
}

}  // namespace

Camera camera_from_sidecar(const std::string& json_path, int frame, const Box2i& display_window) {
  const std::shared_ptr<const json> document = sidecar_document(json_path);
  const json& root = *document;
  try {
    if (root.contains("frames")) {
      const json& frames = root["frames"];
      if (!frames.is_array()) throw_input(json_path, "\"frames\" is not an array");
      for (const json& f : frames) {
        if (!f.is_object() || !f.contains("frame") || !f["frame"].is_number_integer())
          throw_input(json_path, "every entry of \"frames\" needs an integer \"frame\"");
        if (f["frame"].get<long long>() != frame) continue;
        if (std::optional<Camera> c = json_camera(f, display_window, json_path, frame)) return *c;
        throw_input(json_path, "frame " + std::to_string(frame) +
                                   " has neither worldToCamera/worldToNDC nor hfov_deg");
      }
    }
    if (std::optional<Camera> c = json_camera(root, display_window, json_path, frame)) return *c;
  } catch (const json::exception& e) {
    throw_input(json_path, std::string("malformed camera file: ") + e.what());
  } catch (const Error& e) {
    // camera_from_fov reports a bad value as a usage error; in a file it is bad input.
    if (e.kind() == ErrorKind::kUsage || e.file().empty())
      throw_input(json_path, "frame " + std::to_string(frame) + ": " + e.what());
    throw;
  }
  throw_input(json_path, "no camera for frame " + std::to_string(frame));
}

}  // namespace ssgi::detail
