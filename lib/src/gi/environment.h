// What a ray that hits nothing returns: a constant colour or a lat-long environment map.
#pragma once

#include <array>
#include <string>

#include "gi/directions.h"
#include "io/color.h"
#include "ssgi/image.h"

namespace ssgi::detail {

class Environment {
 public:
  // A constant environment of `color` (black by default: renderers usually put sky light in
  // the direct pass already).
  explicit Environment(std::array<float, 3> color = {0, 0, 0});

  // A lat-long map (OpenEXR's convention: +Y up, longitude 0 towards +Z, +pi/2 towards +X).
  // `up` = 'z' takes world +Z as the map's up (Blender worlds): world (x, y, z) is looked up as
  // OpenEXR direction (y, z, x), so that the map's centre faces world +X.
  // Its texels become linear light in the working space through `color` (an 8- or 16-bit
  // map is sRGB-encoded unless --env-colorspace says otherwise).
  // Throws Error(kIO) when the file cannot be read, Error(kInput) when it is not lat-long
  // shaped (width = 2 x height) or has fewer than 3 channels.
  static Environment from_file(const std::string& path, char up, const ColorManagement& color);

  bool is_black() const {
    return map_.empty() && color_[0] == 0 && color_[1] == 0 && color_[2] == 0;
  }
  bool is_constant() const { return map_.empty(); }

  // Radiance arriving from world-space direction `dir` (need not be unit length).
  std::array<float, 3> radiance(const Imath::V3f& dir) const;

 private:
  std::array<float, 3> color_;
  Image map_;  // RGB planes, finite, non-negative
  char up_ = 'y';
};

}  // namespace ssgi::detail
