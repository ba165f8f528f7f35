// The temporal stage. Reprojection finds, for each surface pixel, the same surface point in
// another frame: through the two cameras where the point is static (exact for any frame
// distance, and it predicts the point's depth there), along the renderer's motion vectors where
// it moves (chained through the frames in between). Each bilinear tap of the other frame must
// pass a disocclusion test; what survives is clipped to the current frame's neighbourhood
// (variance clipping, Salvi 2016) before the window averages or the EMA blends it.
#include "gi/temporal.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "buffers.h"
#include "io/camera.h"
#include "parallel.h"
#include "throw.h"

namespace ssgi::detail {
namespace {

// A tap belongs to the reprojected point's surface when it lies within this fraction of the
// point's depth from the point's tangent plane. A plane passes at any slant; a sphere of
// radius R departs from its tangent plane by s^2 / 2R one pixel footprint s away, ~0.2% of
// the depth for the fixtures' ball; a different object is usually tens of per cent away.
constexpr double kPlaneTolerance = 0.01;
// ... and when its normal is within ~25 degrees of the point's (both known). Across a crease
// or onto another object the normal jumps; on a smooth surface it turns by a few degrees per
// pixel at most, except right at silhouettes.
constexpr double kMinNormalCos = 0.9;
// A pixel whose motion vector differs from what the cameras predict for a static point by
// more than this is on a moving object. Renderers' vectors agree with the header cameras to
// ~1e-3 px; below 0.25 px per frame, treating a slow object as static misplaces it by less
// than the 0.5 px a window of +-2 frames tolerates.
constexpr double kMovingThresholdPx = 0.25;
// Forward-backward consistency of motion vectors: the vector back from the tap must undo the
// vector that led to it, to within this many pixels plus this fraction of its length
// (vectors vary across an object by perspective and rotation; between an object and what it
// uncovers they differ by the object's whole motion).
constexpr double kConsistencyPx = 0.5;
constexpr double kConsistencyRelative = 0.2;
// History found on less than this bilinear weight of accepted taps lies almost entirely on a
// rejected pixel: rebuilding it from a neighbour's sliver would be extrapolation.
constexpr double kMinHistoryWeight = 0.05;
// The most histories one reprojection carries at once (reproject's several-history form).
constexpr std::size_t kMaxHistories = 3;
// Variance clipping (Salvi 2016): the box is mean +- gamma * sigma of the 3x3 neighbourhood.
// The indirect light arrives denoised, so its spatial sigma underestimates how much a pixel
// varies from frame to frame (the residual noise is blotches larger than 3x3): sigma gets a
// floor of this fraction of the mean, so that noise is averaged and larger change is clipped.
// Without the floor the clip removes most of the noise reduction; 0.25 gave the least error
// (tests/accuracy/README.md, "Temporal stability").
constexpr double kClipGamma = 1.0;
constexpr double kClipRelativeFloor = 0.25;
constexpr int kClipRadius = 1;
// shared_light_ratio compares two frames on lattices of each with this many samples across the
// square root of its area (a stride of a whole number of samples: at least this many squared),
// a sample being shared when the other frame's sample at its point lies within this fraction
// of the depth predicted (static points: a moving object or noise in the depth pass mostly
// thins the sample, unless it moved to where a static point would be), and says nothing from
// fewer shared samples than this.
constexpr int kSharedLattice = 64;
constexpr double kSharedDepthTolerance = 0.02;
constexpr int kMinShared = 16;

// hypot, not Imath's length(): no overflow or underflow for any finite vector.
double length(const Imath::V2d& v) { return std::hypot(v.x, v.y); }

// The unit vector along v, or 0 when v has no usable direction.
Imath::V3d normalized(const Imath::V3d& v) {
  const double len = std::sqrt(v.dot(v));
  if (!(len > 0) || !std::isfinite(len)) return Imath::V3d(0);
  return v / len;
}
bool is_zero(const Imath::V3d& v) { return v.x == 0 && v.y == 0 && v.z == 0; }

bool has_surface(float z) { return std::isfinite(z) && z > 0; }
float finite_or_zero(float v) { return std::isfinite(v) ? v : 0.0f; }

std::size_t index(const Image& image, int x, int y) {
  return static_cast<std::size_t>(y) * image.width() + x;
}

Imath::V3d load_normal(const GBuffer& g, std::size_t i) {
  if (g.normal.channels() < 3) return Imath::V3d(0);
  return normalized({g.normal.plane(0)[i], g.normal.plane(1)[i], g.normal.plane(2)[i]});
}

// The camera-space transform from frame a's camera to frame b's for static points. A camera
// without a world transform (--fov) does not move: then a and b share their camera space.
Imath::M44d camera_to_camera(const GBuffer& a, const GBuffer& b) {
  if (!a.camera.has_world_transform || !b.camera.has_world_transform) return Imath::M44d();
  return inverse_checked(a.camera.world_to_camera) * b.camera.world_to_camera;
}

// One frame on the way from the current frame to the other one.
struct ChainFrame {
  const GBuffer* g = nullptr;
  Imath::M44d from_current;         // current camera space -> this camera space (static)
  const Image* forward = nullptr;   // motion to the next frame of the chain, if known
  const Image* backward = nullptr;  // motion to the previous frame of the chain, if known
  double ox = 0, oy = 0;            // display coordinates of the data window's origin
};

bool has_motion(const GBuffer& g, const Image& m) {
  return m.channels() >= 2 && m.width() == g.width() && m.height() == g.height();
}

std::vector<ChainFrame> make_chain(const std::vector<const GBuffer*>& frames, int from, int to) {
  const int step = to > from ? 1 : -1;
  std::vector<ChainFrame> chain;
  for (int i = from;; i += step) {
    ChainFrame c;
    c.g = frames[i];
    c.from_current = camera_to_camera(*frames[from], *frames[i]);
    c.ox = c.g->data_window.x0 - c.g->display_window.x0;
    c.oy = c.g->data_window.y0 - c.g->display_window.y0;
    chain.push_back(c);
    if (i == to) break;
  }
  for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
    const GBuffer& a = *chain[k].g;
    const GBuffer& b = *chain[k + 1].g;
    // Vectors point to frame +-1: across a missing frame they do not apply.
    if (b.frame - a.frame != step) continue;
    const Image& forward = step > 0 ? a.motion_next : a.motion_prev;
    const Image& backward = step > 0 ? b.motion_prev : b.motion_next;
    if (has_motion(a, forward)) chain[k].forward = &forward;
    if (has_motion(b, backward)) chain[k + 1].backward = &backward;
  }
  return chain;
}

// What a tap of a chain frame must look like to show the reprojected point.
struct Expectation {
  bool moving = false;
  Imath::V3d point{0, 0, 0};   // where the point is in this frame's camera space if static
  Imath::V3d normal{0, 0, 0};  // its normal there, camera motion compensated (0: unknown)
  // Moving: the allowed |tap depth - point.z|. The vectors give only the 2D motion, so the
  // object may have moved in depth by up to as much as it moved sideways.
  double depth_tolerance = 0;
  Imath::V2d last_step{0, 0};  // moving: the vector that led here, for the consistency test
};

Imath::V2d motion_at(const Image& m, std::size_t i) { return {m.plane(0)[i], m.plane(1)[i]}; }

bool accept_tap(const ChainFrame& f, int tx, int ty, const Expectation& e) {
  const GBuffer& g = *f.g;
  const std::size_t i = index(g.depth, tx, ty);
  const float z = g.depth.plane(0)[i];
  if (!has_surface(z)) return false;
  if (!e.moving) {
    const Imath::V3d p = g.camera.unproject(tx + f.ox + 0.5, ty + f.oy + 0.5, z);
    const Imath::V3d n = is_zero(e.normal) ? normalized(e.point) : e.normal;
    if (!(std::abs((p - e.point).dot(n)) <= kPlaneTolerance * e.point.z)) return false;
  } else {
    if (!(std::abs(z - e.point.z) <= e.depth_tolerance)) return false;
    if (f.backward) {
      const Imath::V2d back = motion_at(*f.backward, i);
      const Imath::V2d sum = back + e.last_step;
      if (!(length(sum) <= kConsistencyPx + kConsistencyRelative * length(e.last_step)))
        return false;
    }
  }
  const Imath::V3d n_tap = load_normal(g, i);
  return is_zero(n_tap) || is_zero(e.normal) || n_tap.dot(e.normal) >= kMinNormalCos;
}

// The current point, static hypothesis, in a chain frame's camera space.
struct StaticPoint {
  Imath::V3d point{0, 0, 0}, normal{0, 0, 0};
  bool in_front = false;
  Imath::V2d pixel{0, 0};  // its projection (display coordinates) when in front
};

StaticPoint static_point(const ChainFrame& f, const Imath::V3d& p, const Imath::V3d& n) {
  StaticPoint s;
  s.point = p * f.from_current;
  Imath::V3d normal(0);
  f.from_current.multDirMatrix(n, normal);
  s.normal = normalized(normal);
  s.in_front = s.point.z > 0 && std::isfinite(s.point.z);
  if (s.in_front) f.g->camera.project(s.point, &s.pixel.x, &s.pixel.y);
  return s;
}

Expectation moving_expectation(const ChainFrame& f, const StaticPoint& s, double current_z,
                               const Imath::V2d& q, const Imath::V2d& last_step) {
  Expectation e;
  e.moving = true;
  e.normal = s.normal;
  e.last_step = last_step;
  // The object's own displacement: the vectors' position against the static prediction,
  // in metres at the point's depth.
  const double z = s.in_front ? s.point.z : current_z;
  e.point = {0, 0, z};
  const Camera& cam = f.g->camera;
  const double dx = s.in_front ? (q.x - s.pixel.x) / cam.fx : 0;
  const double dy = s.in_front ? (q.y - s.pixel.y) / cam.fy : 0;
  e.depth_tolerance = kPlaneTolerance * z + z * std::hypot(dx, dy);
  return e;
}

// The tap nearest to display position q in frame f, false when outside the data window.
bool nearest_tap(const ChainFrame& f, const Imath::V2d& q, int* tx, int* ty) {
  const double u = std::floor(q.x - f.ox), v = std::floor(q.y - f.oy);
  if (!(u >= 0 && u < f.g->width() && v >= 0 && v < f.g->height())) return false;
  *tx = static_cast<int>(u);
  *ty = static_cast<int>(v);
  return true;
}

// Bilinear lookup of each of `histories` (kMaxHistories at most) at display position q over
// the taps that pass the disocclusion tests, tested once for all of them; a tap counts for a
// history where its three values are finite. Writes each history's normalised value to
// out[3 h .. 3 h + 2] (0 where it has too little weight); true when the first has enough.
bool fetch(const ChainFrame& f, const std::vector<const Image*>& histories, const Imath::V2d& q,
           const Expectation& e, double* out) {
  const std::size_t count = histories.size();
  for (std::size_t h = 0; h < 3 * count; ++h) out[h] = 0;
  const double u = q.x - f.ox - 0.5, v = q.y - f.oy - 0.5;
  const int w = f.g->width(), h = f.g->height();
  if (!(u > -1 && u < w && v > -1 && v < h)) return false;
  const double fu = std::floor(u), fv = std::floor(v);
  const int x0 = static_cast<int>(fu), y0 = static_cast<int>(fv);
  const double wx[2] = {1 - (u - fu), u - fu}, wy[2] = {1 - (v - fv), v - fv};
  double sum[kMaxHistories][3] = {}, weight[kMaxHistories] = {};
  for (int j = 0; j < 2; ++j) {
    for (int k = 0; k < 2; ++k) {
      const int tx = x0 + k, ty = y0 + j;
      const double wt = wx[k] * wy[j];
      if (!(wt > 0) || tx < 0 || tx >= w || ty < 0 || ty >= h) continue;
      if (!accept_tap(f, tx, ty, e)) continue;
      for (std::size_t n = 0; n < count; ++n) {
        const Image& history = *histories[n];
        const std::size_t i = index(history, tx, ty);
        const double r = history.plane(0)[i], g = history.plane(1)[i], b = history.plane(2)[i];
        if (!std::isfinite(r) || !std::isfinite(g) || !std::isfinite(b)) continue;
        sum[n][0] += wt * r;
        sum[n][1] += wt * g;
        sum[n][2] += wt * b;
        weight[n] += wt;
      }
    }
  }
  for (std::size_t n = 0; n < count; ++n)
    if (weight[n] >= kMinHistoryWeight)
      for (int c = 0; c < 3; ++c) out[3 * n + c] = sum[n][c] / weight[n];
  return weight[0] >= kMinHistoryWeight;
}

// Reprojects one pixel (x, y) of chain[0] into the last chain frame, each of `histories` into
// out[3 h ..] (fetch); false when the first has no history there.
bool reproject_pixel(const std::vector<ChainFrame>& chain,
                     const std::vector<const Image*>& histories, int x, int y, double* out) {
  const ChainFrame& current = chain.front();
  const GBuffer& g = *current.g;
  const std::size_t i = index(g.depth, x, y);
  const float z = g.depth.plane(0)[i];
  if (!has_surface(z)) return false;
  const Imath::V2d q0{x + current.ox + 0.5, y + current.oy + 0.5};
  const Imath::V3d p = g.camera.unproject(q0.x, q0.y, z);
  const Imath::V3d n = load_normal(g, i);

  const ChainFrame& other = chain.back();
  const StaticPoint s = static_point(other, p, n);

  // Moving when the first step's vector (exact: it is this pixel's own) disagrees with the
  // cameras' prediction for a static point.
  bool moving = false;
  Imath::V2d step(0, 0);
  const bool vectors =
      chain.size() > 1 && std::all_of(chain.begin(), chain.end() - 1,
                                      [](const ChainFrame& c) { return c.forward != nullptr; });
  if (vectors) {
    step = motion_at(*current.forward, i);
    if (std::isfinite(step.x) && std::isfinite(step.y)) {
      const StaticPoint s1 = chain.size() == 2 ? s : static_point(chain[1], p, n);
      moving = !s1.in_front || length(q0 + step - s1.pixel) > kMovingThresholdPx;
    }
  }

  if (!moving) {
    if (!s.in_front) return false;
    Expectation e;
    e.point = s.point;
    e.normal = s.normal;
    return fetch(other, histories, s.pixel, e, out);
  }
  // Along the vectors, checking at each frame in between that the point is still in view.
  Imath::V2d q = q0 + step;
  for (std::size_t k = 1; k + 1 < chain.size(); ++k) {
    const ChainFrame& f = chain[k];
    int tx, ty;
    if (!nearest_tap(f, q, &tx, &ty)) return false;
    if (!accept_tap(f, tx, ty, moving_expectation(f, static_point(f, p, n), z, q, step)))
      return false;
    step = motion_at(*f.forward, index(f.g->depth, tx, ty));
    q = q + step;
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) return false;
  }
  return fetch(other, histories, q, moving_expectation(other, s, z, q, step), out);
}

void check_same_size(const GBuffer& a, const GBuffer& b) {
  if (a.data_window != b.data_window || a.display_window != b.display_window ||
      a.depth.width() != b.depth.width() || a.depth.height() != b.depth.height())
    throw Error(ErrorKind::kInternal, b.path,
                "temporal stage: frames " + std::to_string(a.frame) + " and " +
                    std::to_string(b.frame) + " have different windows");
}

void check_light(const GBuffer& g, const Image& light, const char* what) {
  if (light.channels() != 3 || light.width() != g.depth.width() ||
      light.height() != g.depth.height())
    throw Error(ErrorKind::kInternal, g.path,
                std::string("temporal stage: ") + what + " does not match frame " +
                    std::to_string(g.frame) + "'s data window");
}

// The current light as the stage's starting point: non-finite values count as 0.
Image sanitized(const Image& light) {
  Image out(light.width(), light.height(), 3);
  std::transform(light.data().begin(), light.data().end(), out.data().begin(), finite_or_zero);
  return out;
}

// The clip box of every surface pixel: channels 0-2 the mean, 3-5 the half-widths.
Image clip_boxes(const GBuffer& g, const Image& light) {
  Image boxes(g.width(), g.height(), 6);
  parallel_for_rows(g.height(), [&](int y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!has_surface(g.depth.at(0, x, y))) continue;
      // One pass: where it loses precision (spread far below the mean), the floor dominates.
      double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
      int count = 0;
      for (int yy = std::max(0, y - kClipRadius); yy <= std::min(g.height() - 1, y + kClipRadius);
           ++yy) {
        for (int xx = std::max(0, x - kClipRadius); xx <= std::min(g.width() - 1, x + kClipRadius);
             ++xx) {
          const std::size_t i = index(light, xx, yy);
          if (!has_surface(g.depth.plane(0)[i])) continue;
          for (int c = 0; c < 3; ++c) {
            const double v = finite_or_zero(light.plane(c)[i]);
            sum[c] += v;
            sum2[c] += v * v;
          }
          ++count;
        }
      }
      for (int c = 0; c < 3; ++c) {
        const double mean = sum[c] / count;
        const double var = std::max(0.0, sum2[c] / count - mean * mean);
        const double floor = kClipRelativeFloor * mean;
        boxes.at(c, x, y) = static_cast<float>(mean);
        boxes.at(c + 3, x, y) = static_cast<float>(kClipGamma * std::sqrt(var + floor * floor));
      }
    }
  });
  return boxes;
}

// Moves valid surface pixels of `history` along the line to their box centre until they are
// inside the box (Salvi 2016; clipping towards the centre rather than clamping each channel
// keeps the history's hue).
void clip_to_boxes(const GBuffer& g, const Image& boxes, const Image& valid, Image* history) {
  parallel_for_rows(g.height(), [&](int y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!(valid.at(0, x, y) > 0) || !has_surface(g.depth.at(0, x, y))) continue;
      double t = 1;
      for (int c = 0; c < 3; ++c) {
        const double d = std::abs(history->at(c, x, y) - boxes.at(c, x, y));
        const double half = boxes.at(c + 3, x, y);
        if (d > half * t) t = half > 0 ? d / half : HUGE_VAL;
      }
      if (t <= 1) continue;
      for (int c = 0; c < 3; ++c) {
        const double mean = boxes.at(c, x, y);
        history->at(c, x, y) = static_cast<float>(mean + (history->at(c, x, y) - mean) / t);
      }
    }
  });
}

}  // namespace

std::vector<Image> reproject(const std::vector<const GBuffer*>& frames, int from, int to,
                             const std::vector<const Image*>& histories, Image* valid) {
  const int count = static_cast<int>(frames.size());
  if (from < 0 || from >= count || to < 0 || to >= count)
    throw Error(ErrorKind::kInternal, {}, "temporal stage: frame index out of range");
  if (histories.empty() || histories.size() > kMaxHistories)
    throw Error(ErrorKind::kInternal, {},
                "temporal stage: reproject carries 1 to 3 histories at once");
  const GBuffer& current = *frames[from];
  for (const GBuffer* f : frames) check_same_size(current, *f);
  for (const Image* history : histories) check_light(*frames[to], *history, "history");
  const int w = current.width(), h = current.height();
  std::vector<Image> out;
  for (std::size_t n = 0; n < histories.size(); ++n) out.emplace_back(w, h, 3);
  if (valid) *valid = Image(w, h, 1);
  const std::vector<ChainFrame> chain = make_chain(frames, from, to);
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      double value[3 * kMaxHistories];
      if (!reproject_pixel(chain, histories, x, y, value)) continue;
      const std::size_t i = index(out.front(), x, y);
      for (std::size_t n = 0; n < histories.size(); ++n)
        for (int c = 0; c < 3; ++c) out[n].plane(c)[i] = static_cast<float>(value[3 * n + c]);
      if (valid) valid->plane(0)[i] = 1;
    }
  });
  return out;
}

Image reproject(const std::vector<const GBuffer*>& frames, int from, int to, const Image& history,
                Image* valid) {
  return std::move(reproject(frames, from, to, {&history}, valid).front());
}

Image reproject(const GBuffer& current, const GBuffer& other, const Image& other_history,
                Image* valid) {
  if (other.frame < current.frame) return reproject({&other, &current}, 1, 0, other_history, valid);
  return reproject({&current, &other}, 0, 1, other_history, valid);
}

void clip_history(const GBuffer& current, const Image& current_indirect, const Image& valid,
                  Image* history) {
  check_light(current, current_indirect, "indirect light");
  check_light(current, *history, "history");
  clip_to_boxes(current, clip_boxes(current, current_indirect), valid, history);
}

Image temporal_window(const std::vector<const GBuffer*>& frames,
                      const std::vector<const Image*>& indirect, int center, int radius) {
  const int count = static_cast<int>(frames.size());
  if (static_cast<int>(indirect.size()) != count || center < 0 || center >= count || radius < 0)
    throw Error(ErrorKind::kInternal, {}, "temporal stage: inconsistent window");
  for (int k = 1; k < count; ++k) {
    if (frames[k]->frame <= frames[k - 1]->frame)
      throw Error(ErrorKind::kInternal, {}, "temporal stage: frames not in ascending order");
  }
  const GBuffer& current = *frames[center];
  check_light(current, *indirect[center], "indirect light");
  Image out = sanitized(*indirect[center]);
  // One neighbour at a time into a running sum in double (no overflow for any float light, and
  // the window is the exact mean up to one rounding), always in ascending frame order: the same
  // additions in the same order whatever else the ring holds.
  const std::size_t n = out.plane_size();
  // Started in parallel: copied on one thread, the sums' first touch (3 MB at a 480 x 270 trace
  // grid, in 4 KB pages) is a serial part of every frame.
  UninitializedVector<double> sum(3 * n);
  UninitializedVector<int> frames_used(n);
  parallel_for_rows(current.height(), [&](int y) {
    for (int x = 0; x < current.width(); ++x) {
      const std::size_t i = index(out, x, y);
      for (int c = 0; c < 3; ++c) sum[c * n + i] = out.plane(c)[i];
      frames_used[i] = 1;
    }
  });
  const Image boxes = clip_boxes(current, out);
  for (int k = 0; k < count; ++k) {
    if (k == center || std::abs(frames[k]->frame - current.frame) > radius) continue;
    Image valid;
    Image history = reproject(frames, center, k, *indirect[k], &valid);
    clip_to_boxes(current, boxes, valid, &history);
    parallel_for_rows(current.height(), [&](int y) {
      for (int x = 0; x < current.width(); ++x) {
        const std::size_t i = index(out, x, y);
        if (!(valid.plane(0)[i] > 0)) continue;
        for (int c = 0; c < 3; ++c) sum[c * n + i] += history.plane(c)[i];
        ++frames_used[i];
      }
    });
  }
  parallel_for_rows(current.height(), [&](int y) {
    for (int x = 0; x < current.width(); ++x) {
      const std::size_t i = index(out, x, y);
      for (int c = 0; c < 3; ++c)
        out.plane(c)[i] = static_cast<float>(sum[c * n + i] / frames_used[i]);
    }
  });
  return out;
}

Image temporal_ema(const GBuffer& current, const Image& current_indirect, const GBuffer& previous,
                   const Image& previous_output, float alpha) {
  if (!(alpha > 0 && alpha <= 1))
    throw_usage("EMA weight " + std::to_string(alpha) + " is outside (0, 1]");
  check_light(current, current_indirect, "indirect light");
  Image out = sanitized(current_indirect);
  Image valid;
  Image history = reproject(current, previous, previous_output, &valid);
  clip_history(current, out, valid, &history);
  const double a = alpha;
  parallel_for_rows(current.height(), [&](int y) {
    for (int x = 0; x < current.width(); ++x) {
      const std::size_t i = index(out, x, y);
      if (!(valid.plane(0)[i] > 0)) continue;
      for (int c = 0; c < 3; ++c) {
        float& v = out.plane(c)[i];
        v = static_cast<float>(a * v + (1 - a) * history.plane(c)[i]);
      }
    }
  });
  return out;
}

namespace {

// One direction of shared_light_ratio: over the lattice of `a`'s samples that `b` shows too,
// adds a's light to *sum_a and b's at the same points to *sum_b; returns how many there were.
int add_shared_light(const GBuffer& a, const Image& a_light, const GBuffer& b, const Image& b_light,
                     double* sum_a, double* sum_b) {
  const Imath::M44d to_b = camera_to_camera(a, b);
  const double ax = a.data_window.x0 - a.display_window.x0,
               ay = a.data_window.y0 - a.display_window.y0,
               bx = b.data_window.x0 - b.display_window.x0,
               by = b.data_window.y0 - b.display_window.y0;
  const int w = a.width(), h = a.height();
  const int stride =
      std::max(1, static_cast<int>(std::sqrt(static_cast<double>(w) * h) / kSharedLattice));
  int shared = 0;
  for (int y = stride / 2; y < h; y += stride)
    for (int x = stride / 2; x < w; x += stride) {
      const float z = a.depth.at(0, x, y);
      if (!has_surface(z)) continue;
      const Imath::V3d p = a.camera.unproject(x + ax + 0.5, y + ay + 0.5, z) * to_b;
      if (!(p.z > 0)) continue;
      double px, py;
      b.camera.project(p, &px, &py);
      // The sample whose pixel holds the point: the nearest centre (centres at + 0.5).
      const double fx = std::floor(px - bx), fy = std::floor(py - by);
      if (!(fx >= 0 && fy >= 0 && fx < b.width() && fy < b.height())) continue;
      const int qx = static_cast<int>(fx), qy = static_cast<int>(fy);
      const float zb = b.depth.at(0, qx, qy);
      if (!has_surface(zb) || std::fabs(zb - p.z) > kSharedDepthTolerance * p.z) continue;
      for (int c = 0; c < 3; ++c) {
        *sum_a += finite_or_zero(a_light.at(c, x, y));
        *sum_b += finite_or_zero(b_light.at(c, qx, qy));
      }
      ++shared;
    }
  return shared;
}

}  // namespace

double shared_light_ratio(const GBuffer& a, const Image& a_light, const GBuffer& b,
                          const Image& b_light) {
  check_light(a, a_light, "light");
  check_light(b, b_light, "light");
  // From both frames' lattices, so that the ratio of b to a is exactly the inverse.
  double sum_a = 0, sum_b = 0;
  const int shared = add_shared_light(a, a_light, b, b_light, &sum_a, &sum_b) +
                     add_shared_light(b, b_light, a, a_light, &sum_b, &sum_a);
  if (shared < kMinShared || !(sum_a > 0) || !(sum_b > 0))
    return std::numeric_limits<double>::quiet_NaN();
  return sum_a / sum_b;
}

int ema_preroll_frames(float alpha, double relative_bound) {
  if (!(alpha > 0 && alpha <= 1))
    throw_usage("EMA weight " + std::to_string(alpha) + " is outside (0, 1]");
  if (!(relative_bound > 0 && relative_bound < 1))
    throw_usage("EMA pre-roll bound " + std::to_string(relative_bound) + " is outside (0, 1)");
  if (alpha == 1) return 0;
  // A tiny alpha asks for more frames than any shot has: cap before the conversion.
  const double frames = std::ceil(std::log(relative_bound) / std::log1p(-double{alpha}));
  return static_cast<int>(std::min(frames, 1e9));
}

std::vector<Image> level_window_misses(const std::vector<const TracedLight*>& window,
                                       std::vector<MissColours>* changes) {
  // A frame's misses take the mean colours of the window's frames lit as it is (the surfaces
  // both show reflecting the same light to kSameLight, either way), over those with misses in
  // each group: the view decides which surroundings a border shows, and the frames lit alike
  // agree on them; a frame lit otherwise (a flash, a lamp switched on) keeps its own colours
  // and lends them to no other.
  constexpr double kSameLight = 1.25;
  const std::size_t n = window.size();
  const auto levels = [](const TracedLight& t) {
    return !t.miss_shares.empty() && t.reflected.channels() == 3;
  };
  std::vector<char> alike(n * n, 0);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < n; ++i) {
    alike[i * n + i] = 1;
    for (std::size_t j = i + 1; j < n; ++j)
      if (levels(*window[i]) && levels(*window[j])) pairs.emplace_back(i, j);
  }
  // Each pair on its own (a window of 5 frames has 10).
  parallel_for_rows(static_cast<int>(pairs.size()), [&](int k) {
    const auto [i, j] = pairs[k];
    const double ratio = shared_light_ratio(window[i]->grid, window[i]->reflected, window[j]->grid,
                                            window[j]->reflected);
    alike[i * n + j] = alike[j * n + i] = ratio <= kSameLight && ratio * kSameLight >= 1.0;
  });
  std::vector<Image> out;
  if (changes) changes->assign(n, MissColours{});
  for (std::size_t i = 0; i < n; ++i) {
    const TracedLight* t = window[i];
    Image light = t->light;
    MissColours delta{};
    bool any = false;
    if (levels(*t))
      for (int g = 0; g < 3; ++g) {
        if (!(t->miss_weight[g] > 0)) continue;
        double sum[3] = {};
        int count = 0;
        for (std::size_t j = 0; j < n; ++j) {
          if (!alike[i * n + j] || !(window[j]->miss_weight[g] > 0)) continue;
          for (int c = 0; c < 3; ++c) sum[c] += window[j]->miss_colours[g][c];
          ++count;
        }
        for (int c = 0; c < 3; ++c)
          delta[g][c] = static_cast<float>(sum[c] / count - t->miss_colours[g][c]);
        any = any || count > 1;
      }
    if (changes && any) (*changes)[i] = delta;
    if (any)
      parallel_for_rows(light.height(), [&](int y) {
        const std::size_t row = static_cast<std::size_t>(y) * light.width();
        for (int x = 0; x < light.width(); ++x) {
          const std::size_t s = row + x;
          for (int c = 0; c < 3; ++c) {
            float d = 0;
            for (int g = 0; g < 3; ++g) d += t->miss_shares.plane(g)[s] * delta[g][c];
            light.plane(c)[s] = std::max(light.plane(c)[s] + d, 0.0f);
          }
        }
      });
    out.push_back(std::move(light));
  }
  return out;
}

void add_continued_light(const TracedLight& own, const Image& continued,
                         const Image& continued_shares, const MissColours& change,
                         Image* filtered) {
  const Image& shares = own.miss_shares;
  const bool relevel = shares.channels() == 3 && continued_shares.channels() == 3 &&
                       continued_shares.plane_size() == filtered->plane_size();
  for (int c = 0; c < 3; ++c) {
    float* out = filtered->plane(c);
    const float *with = continued.plane(c), *without = own.light.plane(c);
    for (std::size_t i = 0; i < filtered->plane_size(); ++i) {
      float found = 0;
      if (relevel)
        for (int g = 0; g < 3; ++g)
          found += (shares.plane(g)[i] - continued_shares.plane(g)[i]) * change[g][c];
      out[i] = std::max(out[i] + (with[i] - without[i]) - found, 0.0f);
    }
  }
}

Image filter_window(const std::vector<const TracedLight*>& window, int center, int radius,
                    const ContinuedLight* continued) {
  std::vector<MissColours> changes;
  const std::vector<Image> levelled = level_window_misses(window, &changes);
  std::vector<const GBuffer*> frames;
  std::vector<const Image*> light;
  for (std::size_t i = 0; i < window.size(); ++i) {
    frames.push_back(&window[i]->grid);
    light.push_back(&levelled[i]);
  }
  Image filtered = temporal_window(frames, light, center, radius);
  if (continued)
    add_continued_light(*window[center], continued->light, continued->miss_shares, changes[center],
                        &filtered);
  return filtered;
}

}  // namespace ssgi::detail
