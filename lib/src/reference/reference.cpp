#include "reference/reference.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "gi/directions.h"
#include "gi/surface_model.h"
#include "parallel.h"
#include "ssgi/error.h"

namespace ssgi::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Embree reports errors through a callback; the first message is kept for the exception.
void keep_first_error(void* user, RTCError, const char* message) {
  auto* first = static_cast<std::string*>(user);
  if (first->empty()) *first = message ? message : "unknown error";
}

struct ReleaseDevice {
  void operator()(RTCDevice device) const { rtcReleaseDevice(device); }
};
struct ReleaseScene {
  void operator()(RTCScene scene) const { rtcReleaseScene(scene); }
};
struct ReleaseGeometry {
  void operator()(RTCGeometry geometry) const { rtcReleaseGeometry(geometry); }
};
using GeometryHandle = std::unique_ptr<RTCGeometryTy, ReleaseGeometry>;

// An Embree device (it runs on TBB's pool, so --threads limits it too) whose errors become
// ssgi::Error naming the frame's file.
class EmbreeDevice {
 public:
  explicit EmbreeDevice(const std::string& file) : file_(file), device_(rtcNewDevice(nullptr)) {
    if (!device_) fail("cannot create a device");
    rtcSetDeviceErrorFunction(device_.get(), keep_first_error, error_.get());
  }
  RTCDevice get() const { return device_.get(); }

  // Throws when Embree has reported an error since the last check.
  void check(const char* doing) const {
    if (rtcGetDeviceError(device_.get()) != RTC_ERROR_NONE) fail(doing);
  }

 private:
  [[noreturn]] void fail(const char* doing) const {
    throw Error(ErrorKind::kInternal, file_,
                std::string("Embree: ") + doing + (error_->empty() ? "" : ": " + *error_));
  }

  std::string file_;
  std::unique_ptr<std::string> error_ = std::make_unique<std::string>();
  std::unique_ptr<RTCDeviceTy, ReleaseDevice> device_;
};

// Camera-space points to continuous data-window pixel coordinates, as the march projects them.
struct Screen {
  const Camera& camera;
  float offset_x, offset_y;  // data window origin in display-window pixels

  void project(const Imath::V3f& p, float* sx, float* sy) const {
    *sx = static_cast<float>(camera.cx + camera.fx * p.x / p.z) - offset_x;
    *sy = static_cast<float>(camera.cy - camera.fy * p.y / p.z) - offset_y;
  }

  // Whether `p` is in front of the camera and within pixel (x, y)'s square.
  bool in_pixel(const Imath::V3f& p, int x, int y) const {
    if (!(p.z > 0)) return false;
    float sx, sy;
    project(p, &sx, &sy);
    return std::floor(sx) == static_cast<float>(x) && std::floor(sy) == static_cast<float>(y);
  }
};

// A triangle of the depth mesh: the quad of pixel centres (i, j)..(i+1, j+1) and which half of
// it, above the diagonal (i, j)-(i+1, j+1) or below.
struct MeshTriangle {
  int i, j;
  bool upper;
};

// Each half's corners in outward order (the front face's normal points at the camera: screen y
// runs down), and across the edge from corner k to corner k+1 the neighbouring triangle
// (quad offset, upper).
struct HalfShape {
  int corner[3][2];
  int neighbour[3][3];
};
constexpr HalfShape kUpperHalf = {{{0, 0}, {1, 0}, {1, 1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 0}}};
constexpr HalfShape kLowerHalf = {{{0, 0}, {1, 1}, {0, 1}}, {{0, 0, 1}, {0, 1, 1}, {-1, 0, 1}}};

const HalfShape& shape_of(bool upper) { return upper ? kUpperHalf : kLowerHalf; }

// The reference mesh of reference.h in an Embree scene: per surface pixel a front vertex (index
// = pixel) and a back vertex (pixels + pixel); per mesh triangle its front and back faces and
// the walls along its boundary edges, all triangles of one geometry.
class SlabScene {
 public:
  SlabScene(const GBuffer& g, const DepthMesh& mesh, RTCFilterFunctionN filter)
      : g_(g), mesh_(mesh), device_(g.path), width_(g.width()), height_(g.height()) {
    scene_.reset(rtcNewScene(device_.get()));
    device_.check("creating the scene");
    // Adjacent faces share edges: robust traversal keeps rays from slipping between them.
    rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
    // Hundreds of rays per primitive: the slower, better BVH pays for itself.
    rtcSetSceneBuildQuality(scene_.get(), RTC_BUILD_QUALITY_HIGH);
    const std::vector<Face> faces = collect_faces();
    if (!faces.empty()) attach_geometry(faces, filter);
    rtcCommitScene(scene_.get());
    device_.check("building the scene");
  }

  RTCScene get() const { return scene_.get(); }
  MeshTriangle triangle_of(unsigned prim) const {
    const std::uint32_t code = triangle_of_prim_[prim];
    const int quad = static_cast<int>(code >> 1);
    return {quad % width_, quad / width_, (code & 1) == 0};
  }

 private:
  struct Face {
    std::uint32_t v[3];
  };

  bool exists(int i, int j, bool upper) const { return mesh_.has_triangle(i, j, upper); }

  // Faces in a fixed order (rows, quads, halves), so that the scene and its primitive ids do
  // not depend on threads.
  std::vector<Face> collect_faces() {
    std::vector<Face> faces;
    for (int j = 0; j + 1 < height_; ++j)
      for (int i = 0; i + 1 < width_; ++i)
        for (bool upper : {true, false})
          if (exists(i, j, upper)) add_slab_faces({i, j, upper}, &faces);
    return faces;
  }

  void add_slab_faces(const MeshTriangle& t, std::vector<Face>* faces) {
    const HalfShape& s = shape_of(t.upper);
    const std::uint32_t back = static_cast<std::uint32_t>(width_) * height_;
    std::uint32_t v[3];
    for (int k = 0; k < 3; ++k)
      v[k] = static_cast<std::uint32_t>((t.j + s.corner[k][1]) * width_ + t.i + s.corner[k][0]);
    // The back face looks away from the camera: the front's corners in reverse.
    add(t, {v[0], v[1], v[2]}, faces);
    add(t, {back + v[0], back + v[2], back + v[1]}, faces);
    for (int k = 0; k < 3; ++k) {
      const int* n = s.neighbour[k];
      if (exists(t.i + n[0], t.j + n[1], n[2] != 0)) continue;
      // The wall runs along edge a -> b in the opposite direction to the front face, so that
      // it too points out of the volume.
      const std::uint32_t a = v[k], b = v[(k + 1) % 3];
      add(t, {b, a, back + a}, faces);
      add(t, {b, back + a, back + b}, faces);
    }
  }

  void add(const MeshTriangle& t, const Face& face, std::vector<Face>* faces) {
    faces->push_back(face);
    triangle_of_prim_.push_back(static_cast<std::uint32_t>(t.j * width_ + t.i) << 1 |
                                (t.upper ? 0u : 1u));
  }

  void attach_geometry(const std::vector<Face>& faces, RTCFilterFunctionN filter) {
    const GeometryHandle geometry(rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE));
    device_.check("creating the mesh");
    const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), 2 * pixels));
    auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, sizeof(Face), faces.size()));
    device_.check("allocating the mesh");
    fill_vertices(vertices, vertices + 3 * pixels);
    std::memcpy(indices, faces.data(), faces.size() * sizeof(Face));
    rtcSetGeometryIntersectFilterFunction(geometry.get(), filter);
    rtcCommitGeometry(geometry.get());
    rtcAttachGeometry(scene_.get(), geometry.get());
  }

  // Front vertices at the pixel centres' depths, back vertices at the slabs' far ends; both
  // on the pixel centre's view ray. Background pixels' vertices are unused.
  void fill_vertices(float* front, float* back) const {
    const int ox = g_.data_window.x0 - g_.display_window.x0;
    const int oy = g_.data_window.y0 - g_.display_window.y0;
    for (int y = 0; y < height_; ++y) {
      for (int x = 0; x < width_; ++x) {
        const float z = g_.depth.at(0, x, y);
        const bool surface = std::isfinite(z);
        const double px = x + ox + 0.5, py = y + oy + 0.5;
        const Imath::V3d f = surface ? g_.camera.unproject(px, py, z) : Imath::V3d(0);
        const int pixel = y * width_ + x;
        const Imath::V3d b =
            surface ? g_.camera.unproject(px, py, mesh_.slab_back(z, pixel)) : Imath::V3d(0);
        const std::size_t p = 3 * static_cast<std::size_t>(pixel);
        front[p] = static_cast<float>(f.x), front[p + 1] = static_cast<float>(f.y);
        front[p + 2] = static_cast<float>(f.z);
        back[p] = static_cast<float>(b.x), back[p + 1] = static_cast<float>(b.y);
        back[p + 2] = static_cast<float>(b.z);
      }
    }
  }

  const GBuffer& g_;
  const DepthMesh& mesh_;
  EmbreeDevice device_;
  int width_, height_;
  std::unique_ptr<RTCSceneTy, ReleaseScene> scene_;
  // Per primitive its triangle: quad index (top-left pixel) x 2, + 1 for the lower half. Four
  // bytes, not a MeshTriangle: this table is read once per hit and must stay in cache.
  std::vector<std::uint32_t> triangle_of_prim_;
};

// One ray's query: Embree hands the filter the address of `embree`, the first member, from
// which it finds whose ray it is.
struct RayQuery {
  RTCIntersectContext embree;
  const Screen* screen;
  int self_x, self_y;
};

// Rejects hits in the ray's own pixel's square: the march does not look there either.
void skip_own_pixel(const RTCFilterFunctionNArguments* args) {
  const auto* query = reinterpret_cast<const RayQuery*>(args->context);
  for (unsigned k = 0; k < args->N; ++k) {
    if (args->valid[k] == 0) continue;
    const float t = RTCRayN_tfar(args->ray, args->N, k);
    const Imath::V3f p{
        RTCRayN_org_x(args->ray, args->N, k) + t * RTCRayN_dir_x(args->ray, args->N, k),
        RTCRayN_org_y(args->ray, args->N, k) + t * RTCRayN_dir_y(args->ray, args->N, k),
        RTCRayN_org_z(args->ray, args->N, k) + t * RTCRayN_dir_z(args->ray, args->N, k)};
    if (query->screen->in_pixel(p, query->self_x, query->self_y)) args->valid[k] = 0;
  }
}

// The part [*f_lo, *f_hi] of the screen segment s0 + f (s1 - s0), f in [0, 1], inside the box
// [x0, x1] x [y0, y1] (Liang-Barsky); false when it misses the box.
bool clip_segment(float sx0, float sy0, float dx, float dy, float x0, float y0, float x1, float y1,
                  float* f_lo, float* f_hi) {
  *f_lo = 0.0f, *f_hi = 1.0f;
  auto clip = [&](float p, float q) {
    if (p == 0) return q >= 0;
    const float r = q / p;
    if (p < 0) {
      if (r > *f_hi) return false;
      *f_lo = std::max(*f_lo, r);
    } else {
      if (r < *f_lo) return false;
      *f_hi = std::min(*f_hi, r);
    }
    return true;
  };
  return clip(-dx, sx0 - x0) && clip(dx, x1 - sx0) && clip(-dy, sy0 - y0) && clip(dy, y1 - sy0) &&
         *f_lo <= *f_hi;
}

class ReferenceTracer {
 public:
  ReferenceTracer(const GBuffer& g, const GiSettings& settings, const SurfaceModel& model)
      : g_(g),
        mesh_(g.depth, feature_thickness(g, model)),
        screen_{g.camera, static_cast<float>(g.data_window.x0 - g.display_window.x0),
                static_cast<float>(g.data_window.y0 - g.display_window.y0)},
        tfar_(settings.max_distance > 0 ? static_cast<float>(settings.max_distance) : kInf),
        scene_(g, mesh_, skip_own_pixel) {}

  // The pixel whose light the ray from `o` along unit `d`, cast from pixel (x, y), brings; -1
  // for a miss.
  int trace(const Imath::V3f& o, const Imath::V3f& d, int x, int y) const {
    if (!std::isfinite(o.x + o.y + o.z + d.x + d.y + d.z)) return -1;
    RayQuery query;
    rtcInitIntersectContext(&query.embree);
    query.screen = &screen_;
    query.self_x = x;
    query.self_y = y;
    RTCRayHit rh;
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = tfar_;
    rh.ray.time = 0.0f;
    rh.ray.mask = static_cast<unsigned>(-1);  // masks are enabled: 0 would hit nothing
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_.get(), &query.embree, &rh);
    float t_end = tfar_;
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      const bool enters = rh.hit.Ng_x * d.x + rh.hit.Ng_y * d.y + rh.hit.Ng_z * d.z < 0;
      if (enters) return light_at(scene_.triangle_of(rh.hit.primID), o + rh.ray.tfar * d);
      t_end = rh.ray.tfar;
    }
    return light_where_counting_starts(o, d, t_end, x, y);
  }

 private:
  int light_at(const MeshTriangle& t, const Imath::V3f& p) const {
    float sx, sy;
    screen_.project(p, &sx, &sy);
    // surface_at's rule applied to the triangle the hit is on, which surface_at might not pick
    // for a point on an edge or a wall.
    return mesh_.heaviest_vertex(t.i, t.j, t.upper, sx - 0.5f - static_cast<float>(t.i),
                                 sy - 0.5f - static_cast<float>(t.j));
  }

  // A ray that met no entry before t_end (it left the volume there, or met nothing) is either
  // outside the volume all along, or inside it where it starts to count: at its origin when that
  // is outside its own pixel, or where it leaves its own pixel. Tests both points the march's
  // way (the mesh surface there, and the ray's perspective-correct depth) and returns the light
  // of the first one inside, or -1.
  int light_where_counting_starts(const Imath::V3f& o, const Imath::V3f& d, float t_end, int x,
                                  int y) const {
    float t = std::min(t_end, kFarFactor * o.z);
    if (d.z < 0) t = std::min(t, (o.z - kNearFraction * o.z) / -d.z);
    if (!(t > 0)) return -1;
    const Imath::V3f e = o + t * d;
    float sx0, sy0, sx1, sy1;
    screen_.project(o, &sx0, &sy0);
    screen_.project(e, &sx1, &sy1);
    const float dx = sx1 - sx0, dy = sy1 - sy0;
    if (!std::isfinite(dx) || !std::isfinite(dy)) return -1;
    const float h0 = 1.0f / o.z, h1 = 1.0f / e.z;
    auto light_inside_at = [&](float f) {
      MeshPoint surface;
      if (!mesh_.surface_at(sx0 + dx * f, sy0 + dy * f, &surface)) return -1;
      const float h = h0 + (h1 - h0) * f;
      const float z = h > 0 ? 1.0f / h : kInf;
      return z >= surface.z && z <= surface.back_z ? surface.pixel : -1;
    };
    if (!screen_.in_pixel(o, x, y)) {
      const int light = light_inside_at(0.0f);
      if (light >= 0) return light;
    }
    float f_in, f_out;
    const float fx = static_cast<float>(x), fy = static_cast<float>(y);
    if (!clip_segment(sx0, sy0, dx, dy, fx, fy, fx + 1, fy + 1, &f_in, &f_out) || f_out >= 1)
      return -1;
    const float length_px = std::max(std::fabs(dx), std::fabs(dy));
    return light_inside_at(std::min(1.0f, f_out + kPastEdgePx / length_px));
  }

  const GBuffer& g_;
  DepthMesh mesh_;
  Screen screen_;
  float tfar_;
  SlabScene scene_;
};

// Pixel (x, y)'s rays (the march's, PixelRays): the pixel each one's light comes from, -1 for
// a miss, into hit[0, rays); the number of misses and the sums of what `misses` gives them, in
// ray order, into *missed, env[3] and cube[kCubeFaces].
void trace_reference_pixel(const GBuffer& g, const GiSettings& settings,
                           const ReferenceTracer& tracer, const MissModel& misses, int x, int y,
                           std::int32_t* hit, int* missed, float env[3], float cube[kCubeFaces]) {
  const PixelRays rays(g, settings, x, y);
  std::fill(env, env + 3, 0.0f);
  std::fill(cube, cube + kCubeFaces, 0.0f);
  *missed = 0;
  for (int k = 0; k < settings.rays; ++k) {
    float jitter;  // the march's; Embree needs none
    const Imath::V3f d = rays.direction(k, &jitter);
    const int end = tracer.trace(rays.origin(), d, x, y);
    hit[k] = end >= 0 ? mark_hit(g, end, rays.origin()) : end;
    if (end >= 0) continue;
    ++*missed;
    misses.add(d, 1.0f, env, cube);
  }
}

}  // namespace

RayHits trace_reference(const GBuffer& g, const GiSettings& settings, const MissModel& misses) {
  const ReferenceTracer tracer(g, settings, SurfaceModel{static_cast<float>(settings.thickness)});
  const int w = g.width(), h = g.height();
  RayHits hits(g, settings.rays);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      if (!g.is_surface(x, y)) continue;
      const std::size_t pixel = static_cast<std::size_t>(y) * w + x;
      int missed;
      float env[3], cube[kCubeFaces];
      trace_reference_pixel(g, settings, tracer, misses, x, y, &hits.hit[pixel * hits.rays],
                            &missed, env, cube);
      hits.store_misses(pixel, missed, env, cube);
    }
  });
  return hits;
}

struct ReferenceHits::Impl {
  Impl(const GBuffer& g, const GiSettings& settings, const MissModel& misses)
      : g(g),
        settings(settings),
        tracer(g, settings, SurfaceModel{static_cast<float>(settings.thickness)}),
        misses(misses) {}

  // Row y's hits into `begin` (width + 1 offsets) and `pixel`, as weighted_from_rays packs
  // them; its miss shares, environment light and cube shares into miss, env and cube.
  void trace_row(int y, std::vector<std::uint32_t>* begin, std::vector<std::int32_t>* pixel) {
    const int w = g.width();
    const float inv = 1.0f / static_cast<float>(settings.rays);
    std::vector<std::int32_t> rays(settings.rays);
    begin->resize(w + 1);
    pixel->clear();
    for (int x = 0; x < w; ++x) {
      (*begin)[x] = static_cast<std::uint32_t>(pixel->size());
      if (!g.is_surface(x, y)) continue;
      int missed;
      float env_sum[3], cube_sum[kCubeFaces];
      trace_reference_pixel(g, settings, tracer, misses, x, y, rays.data(), &missed, env_sum,
                            cube_sum);
      for (const std::int32_t hit : rays)
        if (hit >= 0) pixel->push_back(hit);
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      miss.plane(0)[p] = static_cast<float>(missed) * inv;
      for (int ch = 0; ch < 3; ++ch) env.plane(ch)[p] = env_sum[ch] * inv;
      for (int f = 0; f < kCubeFaces; ++f) cube.plane(f)[p] = cube_sum[f] * inv;
    }
    (*begin)[w] = static_cast<std::uint32_t>(pixel->size());
  }

  const GBuffer& g;
  const GiSettings& settings;
  const ReferenceTracer tracer;
  const MissModel& misses;
  Image miss, env, cube;
  int kept_rows = 0;  // rows [0, kept_rows) keep their hits once traced
  struct Row {
    bool traced = false;
    std::vector<std::uint32_t> begin;
    std::vector<std::int32_t> pixel;
  };
  std::vector<Row> rows;
};

std::size_t ReferenceHits::row_bytes(int width, int rays) {
  return static_cast<std::size_t>(width) * rays * sizeof(std::int32_t) +
         (static_cast<std::size_t>(width) + 1) * sizeof(std::uint32_t);
}

ReferenceHits::ReferenceHits(const GBuffer& g, const GiSettings& settings, const MissModel& misses,
                             std::size_t budget_bytes)
    : impl_(std::make_unique<Impl>(g, settings, misses)) {
  const int w = g.width(), h = g.height();
  impl_->miss = Image(w, h, 1);
  impl_->env = Image(w, h, 3);
  impl_->cube = Image(w, h, kCubeFaces);
  impl_->rows.resize(h);
  // A single bounce reads each row once: nothing to keep.
  if (settings.bounces > 1)
    impl_->kept_rows = static_cast<int>(
        std::min<std::size_t>(h, budget_bytes / row_bytes(w, std::max(1, settings.rays))));
}

ReferenceHits::~ReferenceHits() = default;

HitRow ReferenceHits::row(int by, HitScratch* scratch) const {
  Impl::Row& kept = impl_->rows[by];
  HitRow r;
  r.uniform_weight = 1.0f / static_cast<float>(impl_->settings.rays);
  if (by < impl_->kept_rows) {
    if (!kept.traced) impl_->trace_row(by, &kept.begin, &kept.pixel);
    kept.traced = true;
    r.begin = kept.begin.data();
    r.pixel = kept.pixel.data();
    return r;
  }
  // Traced again for each bounce: the same rays meet the same pixels. The first tracing also
  // set the row's miss shares, environment light and cube shares, which tracing again rewrites
  // unchanged.
  impl_->trace_row(by, &scratch->begin, &scratch->pixel);
  r.begin = scratch->begin.data();
  r.pixel = scratch->pixel.data();
  return r;
}

const Image& ReferenceHits::miss() const { return impl_->miss; }
const Image& ReferenceHits::env() const { return impl_->env; }
const Image& ReferenceHits::cube() const { return impl_->cube; }

}  // namespace ssgi::detail
