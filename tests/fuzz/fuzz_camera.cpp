// libFuzzer target: the camera metadata parsers. The first byte picks one:
//   even: the rest is a camera sidecar (JSON) read for frames 1 and 1001;
//   odd:  the rest gives the floats of the header attributes the camera readers look at
//         (worldToCamera, worldToNDC, screenWindowCenter/Width, pixelAspectRatio, cameraFov,
//         CameraFocalLength, CameraFilmApertureHorizontal), on a display window of its own.
// An ssgi::Error is a refusal (fine); a crash, a sanitizer report or a camera that is not
// finite where it was accepted is a finding.
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/camera_header.h"
#include "ssgi/error.h"
#include "ssgi/log.h"

namespace {

// Reads floats from the fuzz input, zeros once it runs out.
struct Floats {
  const std::uint8_t* data;
  std::size_t size;
  template <typename T = float>
  T next() {
    T v = 0;
    if (size >= sizeof v) {
      std::memcpy(&v, data, sizeof v);
      data += sizeof v, size -= sizeof v;
    }
    return v;
  }
};

void check(const ssgi::Camera& c) {
  const double values[] = {c.fx, c.fy, c.cx, c.cy};
  for (double v : values)
    if (!std::isfinite(v)) {
      std::fprintf(stderr, "accepted a camera with fx %g fy %g cx %g cy %g\n", c.fx, c.fy, c.cx,
                   c.cy);
      std::abort();
    }
}

void sidecar(const std::uint8_t* data, std::size_t size) {
  static const std::string path = [] {
    const char* tmp = std::getenv("TMPDIR");
    return std::string(tmp && *tmp ? tmp : "/tmp") + "/ssgi_fuzz_camera." +
           std::to_string(getpid()) + ".json";
  }();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  for (int frame : {1, 1001}) {
    try {
      check(ssgi::detail::camera_from_sidecar(path, frame, {0, 0, 64, 48}));
    } catch (const ssgi::Error&) {
    }
  }
}

void header(const std::uint8_t* data, std::size_t size) {
  Floats f{data, size};
  const int w = 1 + static_cast<int>(f.next<std::uint32_t>() % 4096);
  const int h = 1 + static_cast<int>(f.next<std::uint32_t>() % 4096);
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
  const std::uint32_t present = f.next<std::uint32_t>();
  auto matrix = [&](const char* name) {
    float m[16];
    for (float& v : m) v = f.next();
    spec.attribute(name, OIIO::TypeDesc::TypeMatrix44, m);
  };
  if (present & 1) matrix("worldToCamera");
  if (present & 2) matrix("worldToNDC");
  if (present & 4) matrix("worldToScreen");
  if (present & 8) {
    const float c[2] = {f.next(), f.next()};
    spec.attribute("screenWindowCenter",
                   OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::VEC2), c);
  }
  if (present & 16) spec.attribute("screenWindowWidth", f.next());
  if (present & 32) spec.attribute("PixelAspectRatio", f.next());
  if (present & 64) matrix("worldtocamera");
  if (present & 128) spec.attribute("cameraFov", f.next());
  if (present & 256) spec.attribute("CameraFov", f.next());
  if (present & 512) spec.attribute("CameraFocalLength", f.next());
  if (present & 1024) spec.attribute("CameraFilmApertureHorizontal", f.next());
  try {
    if (const auto c = ssgi::detail::camera_from_header(spec, {0, 0, w, h}, "fuzz.exr")) check(*c);
  } catch (const ssgi::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  ssgi::set_log_handler([](ssgi::LogLevel, const std::string&) {});
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  if (data[0] % 2 == 0)
    sidecar(data + 1, size - 1);
  else
    header(data + 1, size - 1);
  return 0;
}
