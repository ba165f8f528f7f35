// Reading a whole EXR into named float planes, for the accuracy tools (not the library: these
// tools read renderer passes the library deliberately does not).
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace accuracy {

using Planes = std::map<std::string, std::vector<float>>;

// Every channel of subimage 0 of `path`; exits with status 4 when it cannot be read.
inline Planes read_planes(const std::string& path, int* width, int* height) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), OIIO::geterror().c_str());
    std::exit(4);
  }
  const OIIO::ImageSpec& spec = in->spec();
  *width = spec.width;
  *height = spec.height;
  const int n = spec.nchannels;
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
  std::vector<float> data(pixels * n);
  if (!in->read_image(0, 0, 0, n, OIIO::TypeDesc::FLOAT, data.data())) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), in->geterror().c_str());
    std::exit(4);
  }
  Planes planes;
  for (int c = 0; c < n; ++c) {
    auto& p = planes[spec.channelnames[c]];
    p.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) p[i] = data[i * n + c];
  }
  return planes;
}

// The plane `name`; exits with status 3 when the file has no such channel.
inline const std::vector<float>& plane(const Planes& planes, const std::string& name) {
  const auto it = planes.find(name);
  if (it == planes.end()) {
    std::fprintf(stderr, "missing channel %s\n", name.c_str());
    std::exit(3);
  }
  return it->second;
}

}  // namespace accuracy
