#include "gi/misses.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "buffers.h"
#include "gi/trace_grid.h"
#include "io/camera.h"
#include "parallel.h"

namespace ssgi::detail {
namespace {

Imath::V3f normalized(double x, double y, double z) {
  const double l = std::sqrt(x * x + y * y + z * z);
  if (!(l > 0)) return {0, 0, 0};
  return {static_cast<float>(x / l), static_cast<float>(y / l), static_cast<float>(z / l)};
}

// Pool-adjacent-violators: the non-decreasing sequence nearest `v` in least squares weighted
// by `w` (entries of weight 0 take their neighbours' values).
template <std::size_t N>
std::array<float, N> non_decreasing(const std::array<double, N>& v,
                                    const std::array<double, N>& w) {
  struct Block {
    double value, weight;
    std::size_t count;
  };
  std::vector<Block> blocks;
  for (std::size_t i = 0; i < N; ++i) {
    if (!(w[i] > 0)) {
      if (blocks.empty())
        blocks.push_back({0.0, 0.0, 1});
      else
        ++blocks.back().count;
      continue;
    }
    blocks.push_back({v[i], w[i], 1});
    while (blocks.size() > 1) {
      Block& b = blocks.back();
      Block& a = blocks[blocks.size() - 2];
      if (a.weight > 0 && a.value <= b.value) break;
      // Merge (an empty leading block takes the next block's value).
      const double weight = a.weight + b.weight;
      a.value = weight > 0 ? (a.value * a.weight + b.value * b.weight) / weight : b.value;
      a.weight = weight;
      a.count += b.count;
      blocks.pop_back();
    }
  }
  std::array<float, N> out{};
  std::size_t i = 0;
  for (const Block& b : blocks)
    for (std::size_t k = 0; k < b.count; ++k) out[i++] = static_cast<float>(b.value);
  return out;
}

}  // namespace

MissModel::MissModel(const GBuffer& g, MissMode mode, const Environment& env)
    : env_(env),
      display_w_(g.display_window.width()),
      display_h_(g.display_window.height()),
      offset_x_(g.data_window.x0 - g.display_window.x0),
      offset_y_(g.data_window.y0 - g.display_window.y0),
      mode_(mode) {
  const Camera& cam = g.camera;
  rotate_ = cam.has_world_transform;
  // The world's up. Its axes in camera space are the rows of world_to_camera's rotation (row
  // vectors); of those the camera's x axis runs across (a level camera's x is horizontal), the
  // one nearest the camera's up, with the sign that points up the screen (or, looking straight
  // down or up, the one the view points away from). Without a world transform, camera +y.
  up_ = {0, 1, 0};
  up_name_ = "+y (camera)";
  if (rotate_) {
    const Imath::M44d& m = cam.world_to_camera;
    Imath::V3f world[3];
    for (int i = 0; i < 3; ++i) world[i] = normalized(m[i][0], m[i][1], m[i][2]);
    const Imath::M44d inv = inverse_checked(m);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) camera_to_world_[i][j] = static_cast<float>(inv[i][j]);
    int up = -1;
    for (int pass = 0; pass < 2 && up < 0; ++pass)
      for (int i = 0; i < 3; ++i) {
        if (pass == 0 && std::fabs(world[i].x) > 0.3f) continue;
        if (up < 0 || std::fabs(world[i].y) > std::fabs(world[up].y)) up = i;
      }
    const Imath::V3f& a = world[up];
    const bool flip = std::fabs(a.y) > 1e-3f ? a.y < 0 : a.z > 0;
    up_ = flip ? -a : a;
    up_name_ = std::string(flip ? "-" : "+") + "XYZ"[up] + " (world)";
  }
  // The cube's axes: the horizontal right and forward of the view (the view's forward, or
  // looking straight down or up its up, with the up component taken out), and the world's up.
  Imath::V3f forward{-up_.z * up_.x, -up_.z * up_.y, 1.0f - up_.z * up_.z};
  if (forward.dot(forward) < 1e-6f)
    forward = {-up_.y * up_.x, 1.0f - up_.y * up_.y, -up_.y * up_.z};
  forward = normalized(forward.x, forward.y, forward.z);
  const Imath::V3f right = up_.cross(forward);
  axis_[0] = right, axis_[1] = up_, axis_[2] = forward;

  // Over a lattice of the data window: the sky's share by elevation (the pixels showing no
  // surface), and how much of each cube direction the frame's surfaces near its border face.
  const int w = g.width(), h = g.height();
  const int stride = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(w) * h) / 256));
  // The display window's columns in bands, for the most open side.
  constexpr int kBands = 8;
  // Each lattice point's terms, worked out in parallel; the sums below take them in the
  // lattice's order, so that they are the same bits for any thread count. A point is kept to
  // what the sums need (24 bytes: the lattice is fresh memory every frame, 2 MB at 1080p).
  struct Point {
    double border;
    float along[3];  // the normal along each cube axis
    std::uint8_t bin, band;
    bool surface;
  };
  const int columns = (w - stride / 2 + stride - 1) / stride;
  const int rows = (h - stride / 2 + stride - 1) / stride;
  UninitializedVector<Point> lattice(static_cast<std::size_t>(columns) * rows);
  parallel_for_rows(rows, [&](int j) {
    const int y = stride / 2 + j * stride;
    for (int i = 0; i < columns; ++i) {
      const int x = stride / 2 + i * stride;
      Point& pt = lattice[static_cast<std::size_t>(j) * columns + i];
      const Imath::V3d v = cam.view_dir(offset_x_ + x + 0.5, offset_y_ + y + 0.5);
      const float e = static_cast<float>(v.x * up_.x + v.y * up_.y + v.z * up_.z);
      pt.bin = static_cast<std::uint8_t>(
          std::clamp(static_cast<int>((e + 1.0f) * 0.5f * kElevationBins), 0, kElevationBins - 1));
      pt.band = static_cast<std::uint8_t>(
          std::clamp(static_cast<int>((offset_x_ + x + 0.5) / display_w_ * kBands), 0, kBands - 1));
      pt.surface = g.is_surface(x, y);
      if (!pt.surface) continue;
      const float n[3] = {g.normal.at(0, x, y), g.normal.at(1, x, y), g.normal.at(2, x, y)};
      for (int a = 0; a < 3; ++a)
        pt.along[a] = n[0] * axis_[a].x + n[1] * axis_[a].y + n[2] * axis_[a].z;
      pt.border = border_weight(offset_x_ + x + 0.5, offset_y_ + y + 0.5);
    }
  });
  std::array<std::array<double, kElevationBins>, kBands> band_sky{}, band_count{};
  std::array<double, kElevationBins> sky{}, count{};
  double facing[kCubeFaces] = {}, border_total = 0;
  for (const Point& pt : lattice) {
    count[pt.bin] += 1;
    band_count[pt.band][pt.bin] += 1;
    if (!pt.surface) {
      sky[pt.bin] += 1;
      band_sky[pt.band][pt.bin] += 1;
      continue;
    }
    for (int a = 0; a < 3; ++a) {
      const float along = pt.along[a];
      facing[2 * a + (along <= 0 ? 0 : 1)] += pt.border * along * along;
    }
    border_total += pt.border;
  }
  std::array<double, kElevationBins> share{};
  for (int k = 0; k < kElevationBins; ++k) {
    seen_[k] = static_cast<int>(count[k]);
    share[k] = count[k] > 0 ? sky[k] / count[k] : 0;
  }
  // A direction is enclosed as far as the frame's border surfaces face it: fully from three
  // quarters of an average face's weight (the faces' weights sum to border_total; the fraction
  // chosen on the training set, tests/accuracy/training.sh). Behind the camera no surface
  // the frame shows can face: the mean of the two sides stands in for it.
  for (int f = 0; f < kCubeFaces; ++f)
    enclosed_[f] = border_total > 0
                       ? static_cast<float>(std::min(1.0, facing[f] / (0.75 * border_total / 6)))
                       : 0.0f;
  enclosed_[5] = std::max(enclosed_[5], 0.5f * (enclosed_[0] + enclosed_[1]));
  switch (mode) {
    case MissMode::kEnvironment:
    case MissMode::kExtend:
      sky_.fill(1.0f);
      break;
    case MissMode::kFrame:
      sky_.fill(0.0f);
      enclosed_.fill(1.0f);
      break;
    case MissMode::kAuto: {
      // Non-decreasing upwards; beyond the elevations the frame shows, the nearest it shows.
      sky_ = non_decreasing(share, count);
      // An exterior as far as the frame's top shows sky (tests/accuracy/training.sh: a sunlit
      // facade gets the ground before it; a studio without sky keeps its dark surroundings).
      ground_ = sky_.back();
      // A room: a frame whose border shows a ceiling and a floor, under no sky, has walls on
      // the sides the frame cannot show, right, left and behind, though its border may show
      // few surfaces facing them (furniture along an office's sides). Ahead the frame shows
      // the far wall itself, which rays heading forward meet on screen: that enclosure stays
      // as measured (closed too, it lights a room whose far wall is mid-frame too brightly:
      // tests/accuracy/README.md, "Measured and not kept").
      {
        const float room = std::min(enclosed_[2], enclosed_[3]) * (1.0f - ground_);
        for (const int f : {0, 1, 5}) enclosed_[f] = std::max(enclosed_[f], room);
      }
      // Behind the camera: per elevation the most open band's share, fitted the same way, as
      // far as the two sides are not both enclosed (chosen on the training set,
      // tests/accuracy/training.sh: an open square's back is open, a street's is a street).
      std::array<double, kElevationBins> most_open{};
      for (int k = 0; k < kElevationBins; ++k)
        for (int b = 0; b < kBands; ++b)
          if (band_count[b][k] > 0)
            most_open[k] = std::max(most_open[k], band_sky[b][k] / band_count[b][k]);
      sky_behind_ = non_decreasing(most_open, count);
      behind_open_ = 1.0f - std::min(enclosed_[0], enclosed_[1]);
      break;
    }
  }
  if (mode != MissMode::kAuto) sky_behind_ = sky_;
  if (!g.data_window.contains(g.display_window))
    border_held_ = static_cast<float>(held_border_share(g));
}

double MissModel::held_border_share(const GBuffer& g) const {
  const int w = g.display_window.width(), h = g.display_window.height();
  const int stride = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(w) * h) / 256));
  double held = 0, all = 0;
  for (int y = stride / 2; y < h; y += stride)
    for (int x = stride / 2; x < w; x += stride) {
      const double b = border_weight(x + 0.5, y + 0.5);
      all += b;
      if (g.data_window.contains(g.display_window.x0 + x, g.display_window.y0 + y)) held += b;
    }
  return all > 0 ? held / all : 1.0;
}

double MissModel::border_weight(double x, double y) const {
  const double falloff = 1.0 / (kBorder * std::min(display_w_, display_h_));
  const double d = std::min(std::min(x, display_w_ - x), std::min(y, display_h_ - y));
  return std::exp(-std::max(d, 0.0) * falloff);
}

std::array<float, 3> MissModel::environment(const Imath::V3f& d) const {
  if (env_.is_constant() || !rotate_) return env_.radiance(d);
  return env_.radiance(d * camera_to_world_);  // row vectors: world = d * M
}

CubeLight MissModel::cube_light(const TraceGrid& grid, const std::array<float, 4>* light) const {
  // Sums in double, per row in parallel and then over the rows in order: the same bits for any
  // thread count.
  struct Sums {
    double sum[kCubeFaces][3] = {}, weight[kCubeFaces] = {}, total[3] = {}, weight_all = 0;
    std::size_t n = 0;
  };
  // Samples near the display window's border weigh most (border_weight): the surfaces a ray
  // meets beyond the frame continue those at its edge.
  std::vector<double> border(static_cast<std::size_t>(grid.width) + grid.height);
  for (int bx = 0; bx < grid.width; ++bx)
    border[bx] = border_weight(offset_x_ + (bx + 0.5) * grid.scale, display_h_ / 2);
  for (int by = 0; by < grid.height; ++by)
    border[grid.width + by] = border_weight(display_w_ / 2, offset_y_ + (by + 0.5) * grid.scale);
  std::vector<Sums> rows(grid.height);
  parallel_for_rows(grid.height, [&](int by) {
    Sums r;  // a local, kept in registers: the sums are a dependency chain through every sample
    for (int bx = 0; bx < grid.width; ++bx) {
      const std::size_t s = static_cast<std::size_t>(by) * grid.width + bx;
      if (grid.origin[s] < 0) continue;
      const std::array<float, 4>& l = light[s];
      const double b = std::max(border[bx], border[grid.width + by]);
      const float nx = grid.normal.plane(0)[s], ny = grid.normal.plane(1)[s],
                  nz = grid.normal.plane(2)[s];
      for (int i = 0; i < 3; ++i) {
        const float a = nx * axis_[i].x + ny * axis_[i].y + nz * axis_[i].z;
        const int face = 2 * i + (a <= 0 ? 0 : 1);  // a ray along +axis meets normals facing -axis
        const double w = b * a * a;
        r.weight[face] += w;
        for (int c = 0; c < 3; ++c) r.sum[face][c] += w * l[c];
      }
      for (int c = 0; c < 3; ++c) r.total[c] += b * l[c];
      r.weight_all += b;
      ++r.n;
    }
    rows[by] = r;
  });
  double sum[kCubeFaces][3] = {}, weight[kCubeFaces] = {}, total[3] = {}, weight_all = 0;
  std::size_t n = 0;
  for (const Sums& r : rows) {
    for (int f = 0; f < kCubeFaces; ++f) {
      weight[f] += r.weight[f];
      for (int c = 0; c < 3; ++c) sum[f][c] += r.sum[f][c];
    }
    for (int c = 0; c < 3; ++c) total[c] += r.total[c];
    weight_all += r.weight_all;
    n += r.n;
  }
  CubeLight out{};
  if (n == 0 || !(weight_all > 0)) return out;
  // A face few surfaces face is drawn towards the (border-weighted) mean: a prior worth a
  // quarter of an average face's weight (the faces' weights sum to weight_all).
  const double prior = 0.25 * weight_all / kCubeFaces;
  for (int f = 0; f < kCubeFaces; ++f)
    for (int c = 0; c < 3; ++c)
      out[f][c] =
          static_cast<float>((sum[f][c] + prior * total[c] / weight_all) / (weight[f] + prior));
  // A region render: the border the data window does not hold brings no light (misses.h).
  if (border_held_ < 1.0f)
    for (auto& face : out)
      for (float& c : face) c *= border_held_;
  return out;
}

std::string MissModel::describe() const {
  std::string s = "misses (";
  s += mode_ == MissMode::kAuto ? "auto" : mode_ == MissMode::kFrame ? "frame" : "env";
  s += "): up " + up_name_ + "; sky share by elevation -90..90 deg:";
  char buf[64];
  for (int k = 0; k < kElevationBins; ++k) {
    std::snprintf(buf, sizeof buf, " %.2f%s", sky_[k], seen_[k] > 0 ? "" : "*");
    s += buf;
  }
  s += " (* not in the frame); behind the camera, open";
  std::snprintf(buf, sizeof buf, " %.2f:", behind_open_);
  s += buf;
  for (int k = 0; k < kElevationBins; ++k) {
    std::snprintf(buf, sizeof buf, " %.2f", sky_behind_[k]);
    s += buf;
  }
  std::snprintf(buf, sizeof buf, "; ground to the horizon %.2f", ground_);
  s += buf;
  if (border_held_ < 1.0f) {
    std::snprintf(buf, sizeof buf, "; the data window holds %.3f of the border", border_held_);
    s += buf;
  }
  s += "; enclosed right left up down forward back:";
  for (int f = 0; f < kCubeFaces; ++f) {
    std::snprintf(buf, sizeof buf, " %.2f", enclosed_[f]);
    s += buf;
  }
  return s;
}

}  // namespace ssgi::detail
