#include "gi/environment.h"

#include <OpenEXR/ImfEnvmap.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <cmath>

#include "io/oiio_files.h"
#include "ssgi/log.h"
#include "throw.h"

namespace ssgi::detail {

Environment::Environment(std::array<float, 3> color) : color_(color) {}

Environment Environment::from_file(const std::string& path, char up, const ColorManagement& color) {
  auto in = open_image(path);  // a clear error for a missing, empty or special file
  const OIIO::ImageSpec spec = in->spec();
  if (spec.nchannels < 3) throw_input(path, "environment map needs R, G, B channels");
  if (spec.width != 2 * spec.height)
    throw_input(path, "environment map is " + std::to_string(spec.width) + "x" +
                          std::to_string(spec.height) + ", not a 2:1 lat-long map");
  const int r = spec.channelindex("R") >= 0 ? spec.channelindex("R") : 0;
  const int g = spec.channelindex("G") >= 0 ? spec.channelindex("G") : 1;
  const int b = spec.channelindex("B") >= 0 ? spec.channelindex("B") : 2;
  std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
    throw_io(path, "cannot read environment map pixels: " + in->geterror());
  // An 8- or 16-bit map (PNG, JPEG, TIFF), or one that says it is sRGB, holds sRGB-encoded
  // values: light is their decoding, not the values themselves (ColorManagement decides, with
  // the config's sRGB texture space or the built-in curve). Float maps (EXR, HDR) are linear.
  const bool integer = spec.format.basetype != OIIO::TypeDesc::FLOAT &&
                       spec.format.basetype != OIIO::TypeDesc::HALF &&
                       spec.format.basetype != OIIO::TypeDesc::DOUBLE;
  Environment env;
  env.up_ = up;
  env.map_ = Image(spec.width, spec.height, 3);
  const int idx[3] = {r, g, b};
  for (int c = 0; c < 3; ++c) {
    float* dst = env.map_.plane(c);
    for (std::size_t p = 0; p < env.map_.plane_size(); ++p)
      dst[p] = pixels[p * spec.nchannels + idx[c]];
  }
  color.environment_to_working(&env.map_, path, spec.get_string_attribute("oiio:ColorSpace"),
                               integer);
  for (int c = 0; c < 3; ++c) {
    float* dst = env.map_.plane(c);
    // Non-finite or negative texels would poison every pixel that sees them.
    for (std::size_t p = 0; p < env.map_.plane_size(); ++p)
      dst[p] = std::isfinite(dst[p]) ? std::clamp(dst[p], 0.0f, 1e30f) : 0.0f;
  }
  return env;
}

std::array<float, 3> Environment::radiance(const Imath::V3f& dir) const {
  if (map_.empty()) return color_;
  const Imath::V3f d =
      up_ == 'z' ? Imath::V3f(dir.y, dir.z, dir.x) : Imath::V3f(dir.x, dir.y, dir.z);
  if (!(d.length2() > 0)) return {0, 0, 0};
  const int w = map_.width(), h = map_.height();
  const Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
  const Imath::V2f pos = Imf::LatLongMap::pixelPosition(window, d);
  // Bilinear, wrapping in longitude and clamping in latitude.
  const float fx = pos.x, fy = std::clamp(pos.y, 0.0f, static_cast<float>(h - 1));
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const float tx = fx - x0, ty = fy - y0;
  const int y1 = std::min(y0 + 1, h - 1);
  const int xa = ((x0 % w) + w) % w, xb = (xa + 1) % w;
  std::array<float, 3> out;
  for (int c = 0; c < 3; ++c) {
    const float top = map_.at(c, xa, y0) * (1 - tx) + map_.at(c, xb, y0) * tx;
    const float bottom = map_.at(c, xa, y1) * (1 - tx) + map_.at(c, xb, y1) * tx;
    out[c] = top * (1 - ty) + bottom * ty;
  }
  return out;
}

}  // namespace ssgi::detail
