// The surface model: what the depth buffer stands for. The march and the Embree reference both
// use it, so that comparing them measures the tracer and nothing else.
//
// The depth buffer is a triangle mesh through the pixel centres: a vertex at every surface
// pixel's centre at its planar depth z, two triangles per 2x2 quad of pixel centres with the
// fixed diagonal from (x, y) to (x+1, y+1), and a triangle only where its three vertices are
// pairwise connected (each within the other's slab, below). Inverse depth is linear across a
// triangle in screen space (it is a flat triangle in camera space), so a plane stays a plane.
// Behind the surface is a slab: the mesh through each vertex moved back to z * (1 + t), its
// thickness t, i.e. depths from z to z * (1 + t). A ray hits where it enters a slab; the light it
// brings is that of the hit triangle's vertex with the largest barycentric weight. Thickness is
// relative to depth so that the model does not depend on the scene's units. Background pixels
// (z = +inf) are not vertices.
//
// A vertex's thickness is --thickness, unless it lies on a thin feature: a rod, a picket, a blade
// of grass is about as deep as it is wide, so a slab of a tenth of its depth would wall off the
// surface behind it (light from a wall behind a lattice would come off the rods). On screen a
// feature is as wide as the run of pixels on its smooth surface, across and down
// (feature_thickness): a vertex whose narrower run spans n pixels is at most
// kDepthPerWidth x n pixels' worth of its depth thick (n / f of it, f the focal length in
// pixels), in steps of thickness / 64.
//
// A ray that meets a surface from behind sees the surface's unseen back, not the lit front the
// frame shows: it does when its origin lies behind the tangent plane of the vertex whose light
// it brings (the plane through the vertex's point across its normal) by more than
// kBehindTolerance x the vertex's depth (an origin on a crease lies on both faces' planes). It
// then brings the light
// of that vertex's back: its albedo x the indirect light it gathered in the bounce before (its
// direct light and emission belong to the front), and nothing in the first bounce. The tracers
// mark such hits with kSeenFromBehind in the hit's index. (The hit triangle's own plane would
// misjudge the chamfers the mesh puts across concave corners.)
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ssgi/gbuffer.h"
#include "ssgi/image.h"

namespace ssgi::detail {

// Set in a hit's pixel index when the ray meets that surface from behind (see above).
constexpr std::int32_t kSeenFromBehind = std::int32_t{1} << 30;
constexpr float kBehindTolerance = 1e-3f;

// `pixel`, marked kSeenFromBehind when `behind`.
inline std::int32_t mark_side(std::int32_t pixel, bool behind) {
  return behind ? pixel | kSeenFromBehind : pixel;
}

// The pixel of a hit index, without its mark.
inline std::int32_t hit_pixel(std::int32_t hit) { return hit & ~kSeenFromBehind; }

struct SurfaceModel {
  float thickness = 0.1f;  // the thickest slab: that of a vertex on a wide surface
};

// A thin feature's slab is at most this many times as deep as its narrower side is wide.
constexpr float kDepthPerWidth = 2.0f;
// Neighbouring pixels lie on one smooth surface when each is within this fraction of its depth
// of the other's tangent plane.
constexpr float kSmoothTolerance = 0.02f;
// Thicknesses are multiples of model.thickness / kThicknessSteps (the slice tracer's texels
// hold them in 6 bits).
constexpr int kThicknessSteps = 64;

// Each pixel's slab thickness (relative to its depth; see above) for a depth buffer, its unit
// normals and the camera (focal lengths and centre in its pixels).
Image feature_thickness(const Image& depth, const Image& normal, float fx, float fy, float cx,
                        float cy, const SurfaceModel& model);
// The same for a frame's own pixels.
Image feature_thickness(const GBuffer& g, const SurfaceModel& model);

// The mesh front surface at a point of the screen.
struct MeshPoint {
  float z;       // planar depth of the surface
  float back_z;  // and of its slab's back
  int pixel;     // index (y * width + x) of the vertex whose light a hit here brings
};

// The depth buffer seen as the mesh above. Built once per frame: inverse depths and which
// triangles exist are precomputed, so a lookup is four loads and a few multiplies.
class DepthMesh {
 public:
  // `thickness`: each pixel's (feature_thickness), of the size of `depth`.
  DepthMesh(const Image& depth, const Image& thickness);

  int width() const { return width_; }
  int height() const { return height_; }

  // Whether the triangle of quad (i, j) (pixel centres (i, j)..(i+1, j+1)) above the diagonal
  // (`upper`: corners (i,j) (i+1,j) (i+1,j+1)) or below it ((i,j) (i,j+1) (i+1,j+1)) exists.
  bool has_triangle(int i, int j, bool upper) const {
    if (i < 0 || j < 0 || i + 1 >= width_ || j + 1 >= height_) return false;
    return triangles_[static_cast<std::size_t>(j) * width_ + i] & (upper ? kUpper : kLower);
  }

  // Inverse depth of that triangle's surface at offsets (fu, fv) from pixel centre (i, j):
  // barycentric interpolation of the corners' 1/z (exact: the triangle is flat in camera space).
  float inverse_depth_at(int i, int j, bool upper, float fu, float fv) const {
    return interpolate(inverse_depth_, i, j, upper, fu, fv);
  }

  // The same for the back of its slab: the triangle through the corners' slab backs.
  float inverse_back_at(int i, int j, bool upper, float fu, float fv) const {
    return interpolate(inverse_back_, i, j, upper, fu, fv);
  }

  // The far end of the slab of vertex `pixel` for a point of its surface at depth z.
  float slab_back(float z, int pixel) const {
    return z * (1.0f + thickness_[static_cast<std::size_t>(pixel)]);
  }

  // Also joins neighbours that lie on each other's tangent planes (each within kSmoothTolerance
  // of its depth of the other's), as the pixels of a plane seen at a grazing angle do although
  // their depths differ by more than a slab. For views (continuation.h, continue_missed_rays),
  // whose few pixels see much of the scene at such angles; `normal` is per pixel, (fx, fy, cx, cy)
  // the camera in its pixels.
  void join_tangent_neighbours(const Image& depth, const Image& normal, float fx, float fy,
                               float cx, float cy);

  // Keeps the bounds clear_of, tile_clear_of and in_front_at read, per quad and per tile of
  // kTile x kTile quads: for meshes that many rays walk (the views' and the other frames' in
  // continuation.h), which rarely meet most of what they cross. Again after the triangles change.
  void bound_quads();
  bool bounded() const { return !quad_front_.empty(); }
  static constexpr int kTile = 4;

  // Whether a ray whose inverse depth runs from ha to hb over quad (i, j) (pixel centres (i, j)
  // .. (i+1, j+1)) meets no slab there: it lies in front of all its triangles' corners, or
  // behind all their slabs' backs, by more than rounding (a triangle's points lie between its
  // corners). False without bound_quads.
  bool clear_of(int i, int j, float ha, float hb) const {
    if (!bounded()) return false;
    if (i < 0 || j < 0 || i + 1 >= width_ || j + 1 >= height_) return true;
    const std::size_t q = static_cast<std::size_t>(j) * width_ + i;
    return clear(quad_front_[q], quad_back_[q], ha, hb);
  }

  // The same for every quad of tile (ti, tj): quads kTile ti .. kTile ti + kTile - 1 across,
  // likewise down.
  bool tile_clear_of(int ti, int tj, float ha, float hb) const {
    if (!bounded()) return false;
    if (ti < 0 || tj < 0 || ti >= tiles_x_ || tj >= tiles_y_) return true;
    const std::size_t t = static_cast<std::size_t>(tj) * tiles_x_ + ti;
    return clear(tile_front_[t], tile_back_[t], ha, hb);
  }

  // Whether a point at inverse depth h at (sx, sy) (as surface_at) lies in front of every corner
  // of the quad there by more than rounding, so that a surface surface_at finds there lies
  // behind it; *covered then says whether surface_at finds one. False without bound_quads.
  bool in_front_at(float sx, float sy, float h, bool* covered) const {
    if (!bounded()) return false;
    const float u = sx - 0.5f, v = sy - 0.5f;
    const float fi = std::floor(u), fj = std::floor(v);
    const int i = static_cast<int>(fi), j = static_cast<int>(fj);
    if (i < 0 || j < 0 || i + 1 >= width_ || j + 1 >= height_) {
      *covered = false;
      return true;
    }
    if (!(h > quad_front_[static_cast<std::size_t>(j) * width_ + i] * (1.0f + kClearMargin)))
      return false;
    *covered = has_triangle(i, j, u - fi >= v - fj);
    return true;
  }

  // Whether points at depths z0 and z1 of vertices p0 and p1 belong to one continuous surface:
  // each lies within the other's slab.
  bool connected(float z0, int p0, float z1, int p1) const {
    return std::isfinite(z0) && std::isfinite(z1) && z1 <= slab_back(z0, p0) &&
           z0 <= slab_back(z1, p1);
  }

  // The pixel whose light a hit on that triangle at offsets (fu, fv) brings: the corner with
  // the largest barycentric weight (ties in the order (i,j), the middle corner, (i+1,j+1)).
  int heaviest_vertex(int i, int j, bool upper, float fu, float fv) const {
    const float wa = upper ? 1.0f - fu : 1.0f - fv;
    const float wb = upper ? fu - fv : fv - fu;
    const float wc = upper ? fv : fu;
    const int a = j * width_ + i;
    if (wa >= wb && wa >= wc) return a;
    if (wb >= wc) return upper ? a + 1 : a + width_;
    return a + width_ + 1;
  }

  // The surface at continuous data-window pixel coordinates (sx, sy) (pixel (x, y) has its
  // centre at (x + 0.5, y + 0.5)); false where no triangle covers the point.
  bool surface_at(float sx, float sy, MeshPoint* out) const {
    const float u = sx - 0.5f, v = sy - 0.5f;
    const float fi = std::floor(u), fj = std::floor(v);
    const int i = static_cast<int>(fi), j = static_cast<int>(fj);
    const float fu = u - fi, fv = v - fj;
    const bool upper = fu >= fv;
    if (!has_triangle(i, j, upper)) return false;
    out->z = 1.0f / inverse_depth_at(i, j, upper, fu, fv);
    out->back_z = 1.0f / inverse_back_at(i, j, upper, fu, fv);
    out->pixel = heaviest_vertex(i, j, upper, fu, fv);
    return true;
  }

 private:
  float interpolate(const std::vector<float>& v, int i, int j, bool upper, float fu,
                    float fv) const {
    const std::size_t a = static_cast<std::size_t>(j) * width_ + i;
    const std::size_t b = upper ? a + 1 : a + width_;
    const float wa = upper ? 1.0f - fu : 1.0f - fv;
    const float wb = upper ? fu - fv : fv - fu;
    const float wc = upper ? fv : fu;
    return wa * v[a] + wb * v[b] + wc * v[a + width_ + 1];
  }

  static constexpr std::uint8_t kUpper = 1, kLower = 2;
  // Row j's triangles: each exists when `connect` joins its three vertices pairwise.
  template <typename Connect>
  void set_triangles(int j, const Connect& connect);
  int width_, height_;
  std::vector<float> thickness_;         // per pixel
  std::vector<float> inverse_depth_;     // 1/z per pixel
  std::vector<float> inverse_back_;      // 1/(z (1 + thickness)) per pixel
  std::vector<std::uint8_t> triangles_;  // per quad (top-left pixel index): kUpper | kLower
  // Relative to an inverse depth, more than the rounding of a barycentric interpolation.
  static constexpr float kClearMargin = 1e-5f;
  static bool clear(float front, float back, float ha, float hb) {
    return std::min(ha, hb) > front * (1.0f + kClearMargin) ||
           std::max(ha, hb) < back * (1.0f - kClearMargin);
  }
  // Per quad and per tile (bound_quads): its triangles' corners' largest 1/z and smallest
  // 1/back; where there is no triangle, clear at any depth (-inf, +inf).
  std::vector<float> quad_front_, quad_back_, tile_front_, tile_back_;
  int tiles_x_ = 0, tiles_y_ = 0;
};

}  // namespace ssgi::detail
