#include "draw.h"

#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include "io/temporary_files.h"
#include "throw.h"

namespace ssgi_cli {
namespace {

namespace fs = std::filesystem;
namespace IBA = OIIO::ImageBufAlgo;

IBA::TextAlignX text_align_x(Align a) {
  return a == Align::kStart    ? IBA::TextAlignX::Left
         : a == Align::kCenter ? IBA::TextAlignX::Center
                               : IBA::TextAlignX::Right;
}

IBA::TextAlignY text_align_y(Align a) {
  return a == Align::kStart    ? IBA::TextAlignY::Top
         : a == Align::kCenter ? IBA::TextAlignY::Center
                               : IBA::TextAlignY::Bottom;
}

}  // namespace

Canvas::Canvas(int width, int height, Rgb background, std::string font_path)
    : image_(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT)),
      font_path_(std::move(font_path)) {
  std::error_code ec;
  if (!fs::is_regular_file(font_path_, ec))
    ssgi::throw_io(font_path_,
                   "font not found (ssgi draws text with it: install Debian's "
                   "fonts-dejavu-core)");
  const float fill[3] = {background.r, background.g, background.b};
  IBA::fill(image_, fill);
}

void Canvas::blend(int x, int y, Rgb color, float coverage) {
  if (x < 0 || y < 0 || x >= width() || y >= height() || coverage <= 0.0f) return;
  coverage = std::min(coverage, 1.0f);
  float p[3];
  image_.getpixel(x, y, p, 3);
  p[0] += (color.r - p[0]) * coverage;
  p[1] += (color.g - p[1]) * coverage;
  p[2] += (color.b - p[2]) * coverage;
  image_.setpixel(x, y, p, 3);
}

void Canvas::line(int x0, int y0, int x1, int y1, Rgb color, int thickness) {
  const float c[3] = {color.r, color.g, color.b};
  // Thickness grows across the line's minor axis, so that a mostly horizontal line gets
  // taller and a mostly vertical one wider.
  const bool mostly_horizontal = std::abs(x1 - x0) >= std::abs(y1 - y0);
  for (int k = 0; k < std::max(1, thickness); ++k) {
    const int dx = mostly_horizontal ? 0 : k, dy = mostly_horizontal ? k : 0;
    IBA::render_line(image_, x0 + dx, y0 + dy, x1 + dx, y1 + dy, c);
  }
}

void Canvas::box(int x0, int y0, int x1, int y1, Rgb color, bool fill) {
  const float c[3] = {color.r, color.g, color.b};
  IBA::render_box(image_, std::min(x0, x1), std::min(y0, y1), std::max(x0, x1), std::max(y0, y1), c,
                  fill);
}

void Canvas::disk(double cx, double cy, double radius, Rgb color) {
  ring(cx, cy, radius / 2, radius, color);
}

void Canvas::ring(double cx, double cy, double radius, double ring_width, Rgb color) {
  // Coverage of a pixel centre by the annulus [radius - w/2, radius + w/2], with a one-pixel
  // linear ramp at both edges.
  const double inner = std::max(0.0, radius - ring_width / 2), outer = radius + ring_width / 2;
  const int x_lo = static_cast<int>(std::floor(cx - outer - 1));
  const int x_hi = static_cast<int>(std::ceil(cx + outer + 1));
  const int y_lo = static_cast<int>(std::floor(cy - outer - 1));
  const int y_hi = static_cast<int>(std::ceil(cy + outer + 1));
  for (int y = y_lo; y <= y_hi; ++y) {
    for (int x = x_lo; x <= x_hi; ++x) {
      const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
      const double outside = std::clamp(outer - d + 0.5, 0.0, 1.0);
      const double inside = inner <= 0 ? 1.0 : std::clamp(d - inner + 0.5, 0.0, 1.0);
      blend(x, y, color, static_cast<float>(std::min(outside, inside)));
    }
  }
}

void Canvas::text(int x, int y, const std::string& text, int size, Rgb color, Align align_x,
                  Align align_y) {
  const float c[3] = {color.r, color.g, color.b};
  if (!IBA::render_text(image_, x, y, text, size, font_path_, c, text_align_x(align_x),
                        text_align_y(align_y)))
    ssgi::throw_io(font_path_, "cannot draw text with this font: " + image_.geterror());
}

void Canvas::vertical_text(int x, int y, const std::string& text, int size, Rgb color) {
  const TextExtent extent = measure(text, size);
  constexpr int kPad = 2;
  // Drawn upright as coverage in a scratch image, turned a quarter left, then blended in.
  OIIO::ImageBuf upright(
      OIIO::ImageSpec(extent.width + 2 * kPad, extent.height + 2 * kPad, 1, OIIO::TypeDesc::FLOAT));
  IBA::zero(upright);
  const float white = 1.0f;
  if (!IBA::render_text(upright, kPad, kPad, text, size, font_path_, {&white, 1},
                        IBA::TextAlignX::Left, IBA::TextAlignY::Top))
    ssgi::throw_io(font_path_, "cannot draw text with this font: " + upright.geterror());
  const OIIO::ImageBuf turned = IBA::rotate270(upright);
  const OIIO::ROI roi = turned.roi();
  const int x0 = x - roi.width() / 2, y0 = y - roi.height() / 2;
  for (int ty = roi.ybegin; ty < roi.yend; ++ty) {
    for (int tx = roi.xbegin; tx < roi.xend; ++tx) {
      float coverage = 0;
      turned.getpixel(tx, ty, &coverage, 1);
      blend(x0 + tx - roi.xbegin, y0 + ty - roi.ybegin, color, coverage);
    }
  }
}

void Canvas::paste(int x, int y, const OIIO::ImageBuf& picture) {
  if (!IBA::paste(image_, x, y, 0, 0, picture))
    ssgi::throw_io("", "cannot draw a picture: " + image_.geterror());
}

TextExtent Canvas::measure(const std::string& text, int size) const {
  const OIIO::ROI roi = IBA::text_size(text, size, font_path_);
  if (!roi.defined()) ssgi::throw_io(font_path_, "cannot measure text with this font");
  return {roi.width(), roi.height()};
}

void Canvas::write_png(const std::string& path) const {
  ssgi::write_atomically(path, "image", [this](const std::string& tmp, std::string* why) {
    if (image_.write(tmp, OIIO::TypeDesc::UINT8, "png")) return true;
    *why = image_.geterror();
    return false;
  });
}

}  // namespace ssgi_cli
