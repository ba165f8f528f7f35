// Writing the display-referred preview of a frame's composite.
#include "io/preview.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <filesystem>

#include "io/oiio_files.h"
#include "throw.h"

namespace ssgi::detail {

void check_preview_pattern(const std::string& pattern) {
  const std::string extension = std::filesystem::path(pattern).extension().string();
  for (const char* ok : {".png", ".jpg", ".jpeg"})
    if (OIIO::Strutil::iequals(extension, ok)) return;
  throw_usage("--preview '" + pattern + "' must end in .png, .jpg or .jpeg");
}

std::vector<std::pair<std::string, std::string>> preview_attributes(
    const std::vector<std::pair<std::string, std::string>>& provenance,
    const ColorManagement& color) {
  std::vector<std::pair<std::string, std::string>> out = provenance;
  out.emplace_back("ssgi:display", color.display());
  out.emplace_back("ssgi:view", color.view());
  return out;
}

void write_preview(const std::string& path, const GBuffer& frame, const Image& composite,
                   const ColorManagement& color,
                   const std::vector<std::pair<std::string, std::string>>& attributes) {
  const Box2i& display = frame.display_window;
  const Box2i& data = frame.data_window;
  const int w = display.width(), h = display.height();
  Image picture(w, h, 3);
  const int x0 = std::max(display.x0, data.x0), x1 = std::min(display.x1, data.x1);
  const int y0 = std::max(display.y0, data.y0), y1 = std::min(display.y1, data.y1);
  for (int c = 0; c < 3 && x1 > x0; ++c)
    for (int y = y0; y < y1; ++y)
      std::copy_n(composite.plane(c) + static_cast<std::size_t>(y - data.y0) * data.width() +
                      (x0 - data.x0),
                  x1 - x0, &picture.at(c, x0 - display.x0, y - display.y0));
  color.working_to_display(&picture);
  std::vector<float> interleaved(picture.plane_size() * 3);
  for (int c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < picture.plane_size(); ++p)
      interleaved[p * 3 + c] = picture.plane(c)[p];
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
  for (const auto& [name, value] : attributes) spec.attribute(name, value);
  spec.attribute("CompressionQuality", 95);  // JPEG
  write_image_atomically(path, spec, interleaved.data(), "preview");
}

}  // namespace ssgi::detail
