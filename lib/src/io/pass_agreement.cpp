// What a frame's passes say about each other: the depth's normals, the normal pass's space, the
// depth pass against the position pass.
#include "io/pass_agreement.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "io/camera.h"
#include "parallel.h"

namespace ssgi::detail {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// About this many lattice points across and down: enough pixels for a share that one
// surface's bump map or a few silhouettes cannot move, few enough to cost nothing per frame.
constexpr int kLattice = 64;

// Two spaces' transforms closer than this in every entry turn normals alike (a few degrees).
constexpr double kAlike = 0.05;

int lattice_step(int extent) { return std::max(1, extent / kLattice); }

std::string fixed(double v, int digits) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The transform of a normal pass in `space` to the library's camera space (row vectors, the
// upper 3x3 of a matrix acting as n' = n * M): world space goes through the inverse transpose
// of worldToCamera, scaled to determinant 1 so that transforms compare without regard to the
// scene's units; the OpenGL camera looks down -z where ours looks down +z.
Imath::M33d normal_transform(NormalSpace space, const Camera& camera) {
  Imath::M33d m;  // identity
  if (space == NormalSpace::kWorld) {
    const Imath::M44d inv = inverse_checked(camera.world_to_camera);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = inv[j][i];
    const double scale = std::cbrt(std::fabs(m.determinant()));
    if (scale > 0 && std::isfinite(scale)) m *= 1 / scale;
  } else if (space == NormalSpace::kCameraGl) {
    m[2][2] = -1;
  }
  return m;
}

}  // namespace

Image normals_from_depth(const Image& depth, const Camera& camera, const Box2i& display,
                         const Box2i& data) {
  const int w = depth.width(), h = depth.height();
  Image normal(w, h, 3);
  const double ox = data.x0 - display.x0 + 0.5, oy = data.y0 - display.y0 + 0.5;
  auto point = [&](int x, int y, Imath::V3d* p) {
    if (x < 0 || y < 0 || x >= w || y >= h) return false;
    const float z = depth.at(0, x, y);
    if (!std::isfinite(z)) return false;
    *p = camera.unproject(x + ox, y + oy, z);
    return true;
  };
  // A feature one pixel across: both neighbours nearer, or both farther, by more than this
  // fraction of the pixel's depth (input_frame.h).
  constexpr double kFeatureStep = 0.005;
  // The difference towards the neighbour with the smaller depth step, or across a feature one
  // pixel wide at its own depth; false when neither neighbour is a surface.
  auto derivative = [&](const Imath::V3d& c, int x, int y, int dx, int dy, Imath::V3d* d) {
    Imath::V3d a(0), b(0);
    const bool has_a = point(x + dx, y + dy, &a), has_b = point(x - dx, y - dy, &b);
    if (!has_a && !has_b) return false;
    if (has_a && has_b && (a.z - c.z) * (b.z - c.z) > 0 &&
        std::min(std::fabs(a.z - c.z), std::fabs(b.z - c.z)) > kFeatureStep * c.z) {
      const Imath::V3d across = camera.unproject(x + dx + ox, y + dy + oy, c.z);
      *d = across - c;
      return true;
    }
    const bool use_a = has_a && (!has_b || std::fabs(a.z - c.z) <= std::fabs(c.z - b.z));
    *d = use_a ? a - c : c - b;
    return true;
  };
  detail::parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      Imath::V3d c(0);
      if (!point(x, y, &c)) continue;
      const Imath::V3d view = camera.view_dir(x + ox, y + oy);
      Imath::V3d n = -view, du(0), dv(0);
      if (derivative(c, x, y, 1, 0, &du) && derivative(c, x, y, 0, 1, &dv)) {
        const Imath::V3d cr = du.cross(dv);
        const double len = std::sqrt(cr.dot(cr));
        if (len > 0 && std::isfinite(len)) {
          n = cr / len;
          if (n.dot(view) > 0) n = -n;
        }
      }
      normal.at(0, x, y) = static_cast<float>(n.x);
      normal.at(1, x, y) = static_cast<float>(n.y);
      normal.at(2, x, y) = static_cast<float>(n.z);
    }
  });
  return normal;
}

NormalSpaceScores score_normal_spaces(const Image& normal, const Image& depth, const Camera& camera,
                                      const Box2i& display, const Box2i& data) {
  const int w = depth.width(), h = depth.height();
  const double ox = data.x0 - display.x0 + 0.5, oy = data.y0 - display.y0 + 0.5;
  std::array<Imath::M33d, kNormalSpaces.size()> transforms;
  std::array<bool, kNormalSpaces.size()> usable{};
  for (std::size_t s = 0; s < kNormalSpaces.size(); ++s) {
    usable[s] = kNormalSpaces[s] != NormalSpace::kWorld || camera.has_world_transform;
    if (usable[s]) transforms[s] = normal_transform(kNormalSpaces[s], camera);
  }
  // 1/z of a plane is affine in pixel coordinates: where its second difference across the
  // pixel is this small a fraction of it on both axes, the pixel and its four neighbours lie on
  // one plane, and the depth's normal there is that plane's.
  constexpr double kFlat = 1e-3;
  const auto inverse_depth = [&](int x, int y) {
    const float z = depth.at(0, x, y);
    return std::isfinite(z) && z > 0 ? 1.0 / z : kNaN;
  };
  const double agree_cos = std::cos(kAgreeDegrees * 3.14159265358979323846 / 180);
  std::array<std::size_t, kNormalSpaces.size()> agreeing{};
  NormalSpaceScores scores;
  const int sx = lattice_step(w), sy = lattice_step(h);
  for (int y = sy / 2; y < h; y += sy) {
    if (y < 1 || y + 1 >= h) continue;
    for (int x = sx / 2; x < w; x += sx) {
      if (x < 1 || x + 1 >= w) continue;
      const double c = inverse_depth(x, y), l = inverse_depth(x - 1, y),
                   r = inverse_depth(x + 1, y), u = inverse_depth(x, y - 1),
                   d = inverse_depth(x, y + 1);
      if (!(std::fabs(l + r - 2 * c) <= kFlat * c && std::fabs(u + d - 2 * c) <= kFlat * c))
        continue;  // NaN (background) fails too
      const auto point = [&](int px, int py) {
        return camera.unproject(px + ox, py + oy, depth.at(0, px, py));
      };
      Imath::V3d from_depth =
          (point(x + 1, y) - point(x - 1, y)).cross(point(x, y + 1) - point(x, y - 1));
      const double len = from_depth.length();
      if (!(len > 0) || !std::isfinite(len)) continue;
      from_depth /= len;
      if (from_depth.dot(camera.view_dir(x + ox, y + oy)) > 0) from_depth = -from_depth;
      const Imath::V3d stored{normal.at(0, x, y), normal.at(1, x, y), normal.at(2, x, y)};
      if (!std::isfinite(stored.x) || !std::isfinite(stored.y) || !std::isfinite(stored.z) ||
          !(stored.length() > 1e-6))
        continue;
      for (std::size_t s = 0; s < kNormalSpaces.size(); ++s) {
        if (!usable[s]) continue;
        const Imath::M33d& m = transforms[s];
        const Imath::V3d n{stored.x * m[0][0] + stored.y * m[1][0] + stored.z * m[2][0],
                           stored.x * m[0][1] + stored.y * m[1][1] + stored.z * m[2][1],
                           stored.x * m[0][2] + stored.y * m[1][2] + stored.z * m[2][2]};
        const double nl = n.length();
        agreeing[s] += nl > 0 && n.dot(from_depth) >= agree_cos * nl;
      }
      ++scores.samples;
    }
  }
  for (std::size_t s = 0; s < kNormalSpaces.size(); ++s)
    scores.agreeing[s] = !usable[s]       ? kNaN
                         : scores.samples ? static_cast<double>(agreeing[s]) / scores.samples
                                          : 0.0;
  for (std::size_t a = 0; a < kNormalSpaces.size(); ++a)
    for (std::size_t b = 0; b < kNormalSpaces.size(); ++b) {
      double largest = 0;
      if (usable[a] && usable[b])
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            largest = std::max(largest, std::fabs(transforms[a][i][j] - transforms[b][i][j]));
      scores.alike[a][b] = usable[a] && usable[b] && largest < kAlike;
    }
  return scores;
}

NormalSpaceChoice choose_normal_space(NormalSpace said, const NormalSpaceScores& scores,
                                      bool has_world_transform, const std::string& said_by) {
  // A pass in the right space agrees with the depth's normals at nearly every smooth pixel
  // (bump maps and smoothed normals take some away); a wrong space turns most normals by tens of
  // degrees. Below this share the reading is doubtful whichever space wins.
  constexpr double kAgree = 0.5;
  // Fewer smooth surface pixels than this decide nothing.
  constexpr std::size_t kMinSamples = 50;
  const std::size_t n = kNormalSpaces.size();
  const auto index = [&](NormalSpace s) {
    return static_cast<std::size_t>(std::find(kNormalSpaces.begin(), kNormalSpaces.end(), s) -
                                    kNormalSpaces.begin());
  };
  const auto score = [&](std::size_t s) {
    return std::isnan(scores.agreeing[s]) ? -2.0 : scores.agreeing[s];
  };
  std::size_t best = 0;
  for (std::size_t s = 1; s < n; ++s)
    if (score(s) > score(best)) best = s;
  // The best score of a space that turns normals differently from `s`.
  const auto rival = [&](std::size_t s) {
    double r = -2;
    for (std::size_t o = 0; o < n; ++o)
      if (o != s && !scores.alike[s][o]) r = std::max(r, score(o));
    return r;
  };
  std::string all;
  for (std::size_t s = 0; s < n; ++s) {
    if (std::isnan(scores.agreeing[s])) continue;
    all += std::string(all.empty() ? "" : ", ") + normal_space_name(kNormalSpaces[s]) + " " +
           fixed(100 * scores.agreeing[s], 0) + "%";
  }
  const std::string measured = "within " + fixed(kAgreeDegrees, 0) +
                               " degrees of the depth's normals at " + all + " of " +
                               std::to_string(scores.samples) + " pixels";
  NormalSpaceChoice choice;
  const bool decided = said != NormalSpace::kAuto;
  const bool too_few = scores.samples < kMinSamples;
  if (decided) {
    choice.space = said;
    choice.reason = "as " + said_by;
    if (too_few) return choice;
    choice.reason += " (" + measured + ")";
    const std::size_t s = index(said);
    if (best != s && !scores.alike[best][s] && score(best) >= kAgree &&
        score(best) - score(s) >= 0.3)
      choice.warning = std::string("the normals are read in ") + normal_space_name(said) +
                       " space as " + said_by + ", but agree with the depth's in " +
                       normal_space_name(kNormalSpaces[best]) + " space (" + measured +
                       "): give --normal-space " + normal_space_name(kNormalSpaces[best]);
    return choice;
  }
  if (too_few) {
    choice.space = has_world_transform ? NormalSpace::kWorld : NormalSpace::kCamera;
    choice.reason = std::string("taken as ") + normal_space_name(choice.space) +
                    ": too few smooth surface pixels to tell (" + std::to_string(scores.samples) +
                    ")";
    if (scores.samples > 0)
      choice.warning = std::string("too few smooth surface pixels (") +
                       std::to_string(scores.samples) + ") to tell the normals' space: read as " +
                       normal_space_name(choice.space) + " (give --normal-space)";
    return choice;
  }
  choice.space = kNormalSpaces[best];
  choice.reason = "the one that agrees with the depth (" + measured + ")";
  if (score(best) < kAgree || score(best) - rival(best) < 0.2)
    choice.warning = std::string("the normals agree with the depth's in no space clearly (") +
                     measured + "); read as " + normal_space_name(choice.space) +
                     ": give --normal-space, or --normals depth";
  return choice;
}

std::string depth_position_mismatch(const Image& raw_depth, const Image& position,
                                    const Camera& camera, DepthKind kind, double background_depth,
                                    const std::string& depth_name, const std::string& pass_name) {
  const int w = raw_depth.width(), h = raw_depth.height();
  // Each kind's ratio of the stored value to the distance it names; scale-free, so that a
  // depth in other units than the positions (centimetres against metres) still matches.
  constexpr DepthKind kKinds[] = {DepthKind::kPlanarZ, DepthKind::kRadial, DepthKind::kInverseZ,
                                  DepthKind::kNegativeZ};
  constexpr std::size_t kKindCount = sizeof kKinds / sizeof kKinds[0];
  std::vector<double> ratios[kKindCount];
  std::size_t background = 0, background_as_surface = 0;
  float background_value = 0;
  const int sx = lattice_step(w), sy = lattice_step(h);
  for (int y = sy / 2; y < h; y += sy) {
    for (int x = sx / 2; x < w; x += sx) {
      const Imath::V3d p{position.at(0, x, y), position.at(1, x, y), position.at(2, x, y)};
      const float d = raw_depth.at(0, x, y);
      const bool no_position = !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
                               (p.x == 0 && p.y == 0 && p.z == 0);
      if (no_position) {
        ++background;
        double z = d;
        if (kind == DepthKind::kNegativeZ) z = -z;
        if (kind == DepthKind::kInverseZ) z = z > 0 ? 1 / z : kNaN;
        if (std::isfinite(z) && z > 0 && z < background_depth) {
          if (background_as_surface++ == 0) background_value = d;
        }
        continue;
      }
      if (!std::isfinite(d) || d == 0) continue;
      Imath::V3d q;
      camera.world_to_camera.multVecMatrix(p, q);
      if (!(q.z > 0)) continue;
      ratios[0].push_back(d / q.z);
      ratios[1].push_back(d / q.length());
      ratios[2].push_back(d * q.z);
      ratios[3].push_back(-d / q.z);
    }
  }
  std::string out;
  const std::size_t surfaces = ratios[0].size();
  // A filtered pass blends two surfaces at silhouettes: most pixels, not all, must match.
  constexpr double kShare = 0.8, kTolerance = 0.01;
  if (surfaces >= 50) {
    std::size_t matched[kKindCount] = {};
    for (std::size_t k = 0; k < kKindCount; ++k) {
      const double m = median(ratios[k]);
      if (!(m > 0)) continue;
      for (double r : ratios[k]) matched[k] += std::fabs(r / m - 1) <= kTolerance;
    }
    const std::size_t said =
        static_cast<std::size_t>(std::find(kKinds, kKinds + kKindCount, kind) - kKinds);
    std::size_t best = 0;
    for (std::size_t k = 1; k < kKindCount; ++k)
      if (matched[k] > matched[best]) best = k;
    if (matched[said] < kShare * surfaces && matched[best] >= kShare * surfaces)
      out = depth_name + " holds " + depth_kind_name(kKinds[best]) +
            " depth by the position pass " + pass_name + " (" + std::to_string(matched[best]) +
            " of " + std::to_string(surfaces) + " pixels), not " + depth_kind_name(kind) +
            ": give --depth-kind " + depth_kind_name(kKinds[best]);
  }
  if (background_as_surface > 0 && background_as_surface * 2 >= background &&
      background * 100 >= static_cast<std::size_t>((w + sx - 1) / sx) * ((h + sy - 1) / sy)) {
    char text[80];
    std::snprintf(text, sizeof text, " is %g where the position pass ", background_value);
    if (!out.empty()) out += "; ";
    out +=
        depth_name + text + pass_name + " shows no surface, a depth the layout reads as a surface";
    std::snprintf(text, sizeof text, " (its background is at or beyond %g)", background_depth);
    out += std::string(text) + ": those pixels are lit as a wall";
  }
  return out;
}

}  // namespace ssgi::detail
