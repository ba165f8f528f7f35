// What rays that meet nothing bring: the miss model, decided per frame from what the frame
// shows, and shared by the slice tracer, the march and the Embree reference (man/ssgi-gi.7,
// MISSES, says the same for users).
//
// A ray misses when it leaves the frame, or passes behind everything the frame shows. Beyond
// the frame it meets either the sky or a surface the frame does not show (a wall, floor,
// ceiling or the ground). The model takes from the frame:
//  - the world's up (from the camera's world transform);
//  - the sky's share by elevation: the fraction of the frame's pixels at each elevation that
//    show no surface, made non-decreasing upwards (the sky is above the ground) and held at the
//    nearest elevation the frame shows above and below those it shows;
//  - behind the camera, the sky's share of the frame's most open side (of eight bands of the
//    display window's columns, the largest share at each elevation), as far as the frame's two
//    sides are not both enclosed: an open square continues open behind the camera, a street
//    or a room continues as it is in front. Towards the sides the front's share holds;
//  - six cube directions (the view's horizontal right, left, forward and back, up and down)
//    and, for each, how far it is enclosed: how much the frame's surfaces near its border
//    (border_weight) face that way. Behind the camera, which no visible surface can face, is
//    enclosed at least as much as the mean of right and left; in a room (a ceiling and a
//    floor along the border, no sky) right, left and back at least as much as both;
//  - per bounce, each direction's colour: the light of the border surfaces facing it;
//  - how much of that evidence it was given: a data window that does not hold the display
//    window (a region render) holds only part of the border's weight, and what lies in the rest
//    is unknown. The rest counts as surfaces that bring no light: the colours are scaled by the
//    share held (1 for a whole frame or overscan), so that the misses of a crop of a lit centre
//    do not bring that centre's light in place of its darker surroundings'. A crop gets a
//    fraction of the whole frame's light there; --context gives it the whole frame's.
// The part of a miss along d that is not sky is split over the cube's directions by d's squared
// components; each part meets a surface as far as its direction is enclosed, and brings that
// direction's colour (an ambient cube, Mitchell et al. 2006). Under an open sky (the frame's top
// shows sky: an exterior) the ground reaches the horizon: below it, the ground takes the sides'
// parts the more the steeper d heads down, and whatever no side stops. The remainder
// brings the environment in its direction (the --env map or colour, black by default: renderers
// that sample the sky as a light have its light in the direct pass). `--miss env` sends every
// miss to the environment, `frame` encloses every direction under no sky, `auto` measures.
//
// The tracers accumulate, per trace sample, the environment light of their misses and six cube
// shares (MissModel::add); the bounce loop multiplies the shares by that bounce's colours.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>

#include "gi/directions.h"
#include "gi/environment.h"
#include "ssgi/gbuffer.h"
#include "ssgi/settings.h"

namespace ssgi::detail {

struct TraceGrid;

constexpr int kCubeFaces = 6;  // right, left, up, down, forward, back: rays heading that way

// The cube's colours at one bounce: RGB per face.
using CubeLight = std::array<std::array<float, 3>, kCubeFaces>;

class MissModel {
 public:
  static constexpr int kElevationBins = 16;  // equal solid angle: uniform in sin(elevation)

  // The model of frame `g` for `mode`, its sky share measured on a lattice of the data
  // window's pixels (every pixel up to 256 x 256 of them, else a stride that keeps about that).
  MissModel(const GBuffer& g, MissMode mode, const Environment& env);

  // Adds what a miss along camera-space unit direction `d` of weight `w` brings: the
  // environment's light to env[3], the cube's shares to cube[6].
  void add(const Imath::V3f& d, float w, float env[3], float cube[kCubeFaces]) const {
    const float open = 1.0f - sky_share(d);  // what is not sky
    // Below the horizon under an open sky the ground is nearer than the walls the more steeply
    // the ray heads down: it takes that much of the walls' part.
    const float e = d.dot(up_);  // sin(elevation)
    const float ground = e < 0 ? ground_ * std::min(-e * kGroundSteepness, 1.0f) : 0.0f;
    // Each cube direction takes its squared component of the ray, as far as it is enclosed.
    float surfaces = 0;
    for (int i = 0; i < 3; ++i) {
      const float a = d.dot(axis_[i]);
      const int f = 2 * i + (a >= 0 ? 0 : 1);
      const float share = open * a * a * enclosed_[f] * (i == 1 ? 1.0f : 1.0f - ground);
      cube[f] += w * share;
      surfaces += share;
    }
    // What no side stops below the horizon meets the ground, as far as the sky is open.
    if (e < 0 && ground_ > 0 && surfaces < open) {
      const float share = ground_ * (open - surfaces) * enclosed_[3];
      cube[3] += w * share;
      surfaces += share;
    }
    if (env_.is_black() || !(surfaces < 1.0f)) return;
    const std::array<float, 3> l = environment(d);
    for (int c = 0; c < 3; ++c) env[c] += w * (1.0f - surfaces) * l[c];
  }

  // What a ray of weight `w` known to reach the sky along camera-space unit direction `d` brings
  // (a view shows no surface in its direction): the environment's light there, added to
  // light[3].
  void add_sky(const Imath::V3f& d, float w, float light[3]) const {
    if (env_.is_black()) return;
    const std::array<float, 3> l = environment(d);
    for (int c = 0; c < 3; ++c) light[c] += w * l[c];
  }

  // The world's up axis in camera space.
  const Imath::V3f& up() const { return up_; }

  // The share of the sky along camera-space unit direction `d`: the front's share by
  // elevation, turning into the one behind the camera as `d` turns away from the view (in
  // proportion to the cosine of its horizontal angle from straight back, none sideways).
  float sky_share(const Imath::V3f& d) const {
    const float e = d.dot(up_);  // sin(elevation)
    const float f = std::min(std::max((e + 1.0f) * 0.5f * kElevationBins - 0.5f, 0.0f),
                             static_cast<float>(kElevationBins - 1));
    const int k = std::min(static_cast<int>(f), kElevationBins - 2);
    const float t = f - static_cast<float>(k);
    const float front = sky_[k] + t * (sky_[k + 1] - sky_[k]);
    const float ahead = d.dot(axis_[2]);
    if (!(ahead < 0) || !(behind_open_ > 0)) return front;
    const float behind = sky_behind_[k] + t * (sky_behind_[k + 1] - sky_behind_[k]);
    const float across = std::sqrt(std::max(1.0f - e * e, 0.0f));  // the horizontal length
    const float back = across > 0 ? std::min(-ahead / across, 1.0f) : 0.0f;
    return front + back * behind_open_ * (behind - front);
  }

  // The environment's light along camera-space direction `d` (world-space maps rotated).
  std::array<float, 3> environment(const Imath::V3f& d) const;

  // The cube's colours for one bounce: light[s] is trace sample s's light (what it reflects plus
  // albedo x its indirect light; RGB and one unused float), over the samples with an origin.
  CubeLight cube_light(const TraceGrid& grid, const std::array<float, 4>* light) const;

  // One line for -v: the up axis, the sky share by elevation, where it came from.
  std::string describe() const;

  const std::array<float, kElevationBins>& sky_by_elevation() const { return sky_; }

 private:
  // How much a surface at display-window position (x, y) speaks for what lies beyond the
  // frame: exp(-d / (kBorder x the display window's smaller side)), d its distance to the
  // nearest edge.
  double border_weight(double x, double y) const;
  // The border weight of the display window's pixels inside the data window over that of all
  // its pixels, on a lattice of the display window (every pixel up to 256 x 256 of them).
  double held_border_share(const GBuffer& g) const;
  static constexpr double kBorder = 0.1;
  // Below the horizon under an open sky, the ground takes all of a miss's part that would
  // meet a wall from sin(depression) 1 / kGroundSteepness (11.5 degrees) down: walls about
  // five camera heights away, as in the training set's exteriors.
  static constexpr float kGroundSteepness = 5.0f;

  const Environment& env_;
  double display_w_, display_h_;  // the display window's size
  double offset_x_, offset_y_;    // the data window's origin in it
  // The share of the border's weight the data window holds (held_border_share; 1 when it holds
  // the display window): the cube's colours are scaled by it.
  float border_held_ = 1.0f;
  // The cube's axes in camera space: the view's horizontal right, the world's up, the view's
  // horizontal forward; face 2 i is +axis i, 2 i + 1 its opposite (so 5 is behind the camera).
  Imath::V3f axis_[3];
  // Per face, how far a miss heading that way meets a surface rather than the environment.
  std::array<float, kCubeFaces> enclosed_{};
  Imath::V3f up_;  // the world's up axis in camera space
  std::string up_name_;
  std::array<float, kElevationBins> sky_{};
  // Behind the camera: the most open side's share by elevation, and how far it holds there
  // (1 - the lesser of the right and left enclosures).
  std::array<float, kElevationBins> sky_behind_{};
  float behind_open_ = 0;
  // How far the frame is an exterior, whose ground reaches the horizon under every miss below
  // it: the sky's share at the frame's highest elevation (0 indoors and in a studio).
  float ground_ = 0;
  std::array<int, kElevationBins> seen_{};  // trace samples per bin (for describe)
  MissMode mode_;
  bool rotate_ = false;
  Imath::M33f camera_to_world_;  // identity without a world transform
};

}  // namespace ssgi::detail
