// A small canvas for the pictures the tool draws (the sweep's plot, a contact sheet): lines,
// boxes, markers and text on an OIIO ImageBuf, written as PNG. Text uses a named TrueType
// font, since OIIO's default font is not found on Debian 12.
#pragma once

#include <OpenImageIO/imagebuf.h>

#include <string>

namespace ssgi_cli {

// DejaVu Sans from Debian's fonts-dejavu-core.
constexpr const char* kDefaultFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

// A display colour, each channel in [0, 1], written to PNG as is (sRGB values).
struct Rgb {
  float r = 0, g = 0, b = 0;
};

// Where an item sits against its anchor point: left/top, centre, right/bottom.
enum class Align { kStart, kCenter, kEnd };

// The size of a piece of text as drawn: its ink box around the baseline, in pixels.
struct TextExtent {
  int width = 0, height = 0;
};

class Canvas {
 public:
  // A width x height RGB canvas filled with `background`. Throws Error(kIO) naming the font
  // when the file `font_path` is missing.
  Canvas(int width, int height, Rgb background, std::string font_path = kDefaultFontPath);

  int width() const { return image_.spec().width; }
  int height() const { return image_.spec().height; }

  // A straight line between two pixel centres, `thickness` pixels wide (grown downwards and
  // rightwards from the first pixel row or column).
  void line(int x0, int y0, int x1, int y1, Rgb color, int thickness = 1);
  // The rectangle with these corner pixels (inclusive), outlined or filled.
  void box(int x0, int y0, int x1, int y1, Rgb color, bool fill);
  // A filled disk, its edge antialiased over one pixel.
  void disk(double cx, double cy, double radius, Rgb color);
  // A circle outline `width` pixels wide, antialiased.
  void ring(double cx, double cy, double radius, double width, Rgb color);
  // Text anchored at (x, y): align_x places its left edge, centre or right edge there,
  // align_y its top, middle or bottom. Throws Error(kIO) when the font cannot render it.
  void text(int x, int y, const std::string& text, int size, Rgb color,
            Align align_x = Align::kStart, Align align_y = Align::kStart);
  // Text reading from bottom to top (an axis title), centred on (x, y).
  void vertical_text(int x, int y, const std::string& text, int size, Rgb color);
  // Copies the RGB image `picture` (display values in [0, 1]) with its top left corner at (x, y).
  void paste(int x, int y, const OIIO::ImageBuf& picture);
  // What text() would cover.
  TextExtent measure(const std::string& text, int size) const;

  // Writes the canvas as an 8-bit PNG under a hidden temporary name beside `path`, renamed
  // into place when whole (the folder is made when missing). Throws Error(kIO).
  void write_png(const std::string& path) const;

  const OIIO::ImageBuf& image() const { return image_; }

 private:
  // Blends `color` into pixel (x, y) with weight `coverage` in [0, 1]; outside: nothing.
  void blend(int x, int y, Rgb color, float coverage);

  OIIO::ImageBuf image_;
  std::string font_path_;
};

}  // namespace ssgi_cli
