// What a frame's passes say about each other (internal): the normals the depth buffer implies,
// the space a normal pass is in judged by its agreement with them, and whether the depth pass
// holds the distance the layout says when a position pass shows the same surfaces.
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include "io/layout.h"
#include "ssgi/camera.h"
#include "ssgi/image.h"

namespace ssgi::detail {

// Unit camera-space normals facing the camera from the depth buffer's pixel derivatives: the
// camera-space points of the pixel and its neighbours; along each axis the one-sided difference
// with the smaller depth step (so that a depth edge does not bend the normal of the surface on
// either side), the other side where one is background; the normal across the two, turned to
// face the camera. A pixel with no surface neighbour on an axis faces the camera along it, and
// so does a feature one pixel across on that axis (a rod, a blade of grass): a pixel both of
// whose neighbours lie nearer, or both farther, by more than half a per cent of its depth, where
// no plane can lie (its depth along a screen line is monotonic) and either difference would
// turn the normal sideways. `depth` is planar camera z, +inf where there is no surface.
Image normals_from_depth(const Image& depth, const Camera& camera, const Box2i& display,
                         const Box2i& data);

// The spaces a normal pass can be in, as scored below, in NormalSpace's order.
constexpr std::array<NormalSpace, 3> kNormalSpaces = {NormalSpace::kWorld, NormalSpace::kCamera,
                                                      NormalSpace::kCameraGl};

// How well a normal pass read in each space agrees with the depth's normals: the share of
// surface pixels, on a lattice of about 64 x 64 where the depth is smooth around the pixel (so
// that the depth's normal is a plane's), at which the two normals lie within kAgreeDegrees of
// each other, per space of kNormalSpaces. A share, not a mean or median: one plane filling the
// frame (a floor) can look alike in two spaces, every plane cannot. World space scores NaN
// without a world transform. `samples` is how many pixels were compared; `alike`
// says which two spaces turn a normal the same way in this frame (within 0.05 in every entry of
// the scale-free transform: a camera whose axes are the world's), so that either reading is
// right.
constexpr double kAgreeDegrees = 18;
struct NormalSpaceScores {
  std::array<double, 3> agreeing{};
  std::size_t samples = 0;
  bool alike[3][3] = {};
};
NormalSpaceScores score_normal_spaces(const Image& normal, const Image& depth, const Camera& camera,
                                      const Box2i& display, const Box2i& data);

// The space chosen for a pass and the words that say why, for `info` and messages.
struct NormalSpaceChoice {
  NormalSpace space = NormalSpace::kWorld;
  std::string reason;   // e.g. "agrees with the depth's normals (cos 0.99; camera 0.12, ...)"
  std::string warning;  // non-empty when the choice is doubtful or contradicts the data
};

// The space of a pass whose layout says `said` (kAuto: decide). For kAuto the best-scoring
// space, doubtful when it agrees poorly with the depth or hardly better than another space
// whose normals differ. For a given space, a warning when another space agrees clearly
// better: a pass read in the wrong space lights every surface from the wrong side.
NormalSpaceChoice choose_normal_space(NormalSpace said, const NormalSpaceScores& scores,
                                      bool has_world_transform, const std::string& said_by);

// Where a frame has a depth pass and a world position pass: a one-line warning (without the
// file name) when the stored depth is not the distance `kind` says to the positions seen
// through `camera` (which needs a world transform) and another kind matches, or when most
// pixels the position pass shows as background (position exactly 0, 0, 0 or not finite) hold a
// depth the layout reads as a surface; "" when they agree. `raw_depth` is the depth pass as
// stored and `position` its X, Y, Z planes, the same size. Scale-free: depth in other units
// than the positions agrees.
std::string depth_position_mismatch(const Image& raw_depth, const Image& position,
                                    const Camera& camera, DepthKind kind, double background_depth,
                                    const std::string& depth_name, const std::string& pass_name);

}  // namespace ssgi::detail
