// ssgi preview: a contact sheet of the passes of chosen frames, lit by the pipeline with the
// options of run: direct, indirect, gi, composite, and the difference to a truth layer of the
// input or to a reference sequence.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "draw.h"
#include "io/color.h"
#include "io/frame_reader.h"
#include "log.h"
#include "options/run_options.h"
#include "ssgi/run.h"
#include "ssgi/threads.h"
#include "throw.h"
#include "truth_layer.h"

namespace ssgi_cli {
namespace {

namespace fs = std::filesystem;

// Frames shown when --frames is not given: this many, spread over the shot.
constexpr int kDefaultFrames = 4;
// A panel is the data window scaled down to at most this width.
constexpr int kMaxPanelWidth = 400;
constexpr int kGap = 8, kLabelWidth = 84, kTitleHeight = 50, kHeaderHeight = 28,
              kCaptionHeight = 22;
constexpr Rgb kBackground = {0.11f, 0.11f, 0.12f}, kInk = {0.93f, 0.93f, 0.93f},
              kDim = {0.62f, 0.62f, 0.65f}, kNoSurface = {0.24f, 0.24f, 0.25f};

void print_help() {
  std::printf(
      "usage: ssgi preview INPUT -o SHEET.png [--frames LIST] [--truth LAYER]\n"
      "                    [--reference REF.####.exr] [options]\n\n"
      "Lights the chosen frames as 'ssgi run' would (the same options) and draws a labelled\n"
      "sheet: a row per frame with its direct light, indirect light, gi and composite through\n"
      "the preview's display and view, and the difference of the indirect light to a truth\n"
      "layer of the input or to the indirect layer of a reference sequence (red: ssgi too\n"
      "bright, blue: too dark). Without --frames, %d frames spread over the shot.\n\n%s",
      kDefaultFrames, options_help(kPreviewCommand).c_str());
}

// A plane set of `channels` planes, area-averaged down to w x h.
ssgi::Image shrink(const ssgi::Image& from, int w, int h) {
  ssgi::Image to(w, h, from.channels());
  for (int y = 0; y < h; ++y) {
    const int y0 = y * from.height() / h, y1 = std::max(y0 + 1, (y + 1) * from.height() / h);
    for (int x = 0; x < w; ++x) {
      const int x0 = x * from.width() / w, x1 = std::max(x0 + 1, (x + 1) * from.width() / w);
      for (int c = 0; c < from.channels(); ++c) {
        double sum = 0;
        for (int sy = y0; sy < y1; ++sy)
          for (int sx = x0; sx < x1; ++sx) sum += from.at(c, sx, sy);
        to.at(c, x, y) = static_cast<float>(sum / ((y1 - y0) * (x1 - x0)));
      }
    }
  }
  return to;
}

// The first three planes of `image`.
ssgi::Image rgb_of(const ssgi::Image& image) {
  ssgi::Image out(image.width(), image.height(), 3);
  std::copy_n(image.data().begin(), out.data().size(), out.data().begin());
  return out;
}

// The R, G, B channels of `layer` (as compare names channels: <part>.<channel> in a named part)
// of `path`, covering `window` (0 outside the file's data window).
ssgi::Image read_layer(const std::string& path, const std::string& layer,
                       const ssgi::Box2i& window) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) ssgi::throw_io(path, OIIO::Strutil::replace(OIIO::geterror(), "\n", " ", true));
  ssgi::Image out(window.width(), window.height(), 3);
  for (int s = 0; in->seek_subimage(s, 0); ++s) {
    const OIIO::ImageSpec& spec = in->spec();
    const std::string part = spec.get_string_attribute("oiio:subimagename");
    int index[3] = {-1, -1, -1};
    for (int c = 0; c < spec.nchannels; ++c)
      for (int k = 0; k < 3; ++k) {
        const std::string want = layer + "." + "RGB"[k];
        const std::string& name = spec.channelnames[c];
        if (name == want || (!part.empty() && part + "." + name == want)) index[k] = c;
      }
    if (index[0] < 0 || index[1] < 0 || index[2] < 0) continue;
    const int lo = *std::min_element(index, index + 3), hi = *std::max_element(index, index + 3);
    const int n = hi - lo + 1;
    std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * n);
    if (!in->read_image(s, 0, lo, hi + 1, OIIO::TypeDesc::FLOAT, pixels.data()))
      ssgi::throw_io(path, "cannot read " + layer + ": " + in->geterror());
    for (int y = 0; y < spec.height; ++y)
      for (int x = 0; x < spec.width; ++x) {
        const int ox = spec.x + x - window.x0, oy = spec.y + y - window.y0;
        if (ox < 0 || oy < 0 || ox >= window.width() || oy >= window.height()) continue;
        const std::size_t p = (static_cast<std::size_t>(y) * spec.width + x) * n;
        for (int k = 0; k < 3; ++k) {
          const float v = pixels[p + index[k] - lo];
          out.at(k, ox, oy) = std::isfinite(v) ? v : 0.0f;
        }
      }
    return out;
  }
  ssgi::throw_input(path, "has no R,G,B layer '" + layer + "'");
}

// One panel of the sheet before it is drawn: working-space light, or a signed difference.
struct Panel {
  ssgi::Image image;    // 3 channels (light) or 1 (difference), the panel's size
  ssgi::Image surface;  // 1 channel: the fraction of surface pixels (difference panels)
  std::string caption;  // under the panel; empty: none
  bool difference = false;
};

struct Row {
  int frame = 0;
  std::vector<Panel> panels;
};

// The indirect light minus `truth` per pixel (mean of the channels) over surface pixels, its
// relative RMSE (RMSE over surface pixels and channels / the truth's mean there), and the
// truth's mean.
struct Difference {
  ssgi::Image signed_mean, surface;
  double relrmse = 0, truth_mean = 0;
};

Difference difference(const ssgi::GBuffer& g, const ssgi::Image& indirect,
                      const ssgi::Image& truth) {
  Difference d;
  d.signed_mean = ssgi::Image(g.width(), g.height(), 1);
  d.surface = ssgi::Image(g.width(), g.height(), 1);
  double squared = 0, sum = 0;
  std::size_t n = 0;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) {
      if (!g.is_surface(x, y)) continue;
      double mean = 0;
      for (int c = 0; c < 3; ++c) {
        const double e = indirect.at(c, x, y) - truth.at(c, x, y);
        squared += e * e;
        sum += truth.at(c, x, y);
        mean += e / 3;
      }
      n += 3;
      d.signed_mean.at(0, x, y) = static_cast<float>(mean);
      d.surface.at(0, x, y) = 1;
    }
  d.truth_mean = n ? sum / n : 0;
  d.relrmse = n && d.truth_mean > 0 ? std::sqrt(squared / n) / d.truth_mean : 0;
  return d;
}

// The picture of a light panel through the display and view.
OIIO::ImageBuf light_picture(const ssgi::Image& working, const ssgi::ColorManagement& color) {
  ssgi::Image shown = working;
  color.working_to_display(&shown);
  OIIO::ImageBuf buf(OIIO::ImageSpec(shown.width(), shown.height(), 3, OIIO::TypeDesc::FLOAT));
  for (int y = 0; y < shown.height(); ++y)
    for (int x = 0; x < shown.width(); ++x) {
      const float p[3] = {shown.at(0, x, y), shown.at(1, x, y), shown.at(2, x, y)};
      buf.setpixel(x, y, p, 3);
    }
  return buf;
}

// A difference as colour: red-orange where ssgi is brighter, blue where darker, black where
// equal; grey where there is no surface. `scale` maps to full strength; sqrt for visibility.
OIIO::ImageBuf difference_picture(const Panel& panel, double scale) {
  const ssgi::Image& d = panel.image;
  OIIO::ImageBuf buf(OIIO::ImageSpec(d.width(), d.height(), 3, OIIO::TypeDesc::FLOAT));
  for (int y = 0; y < d.height(); ++y)
    for (int x = 0; x < d.width(); ++x) {
      const float cover = panel.surface.at(0, x, y);
      // Surface pixels hold the mean over the covered ones; the area average diluted it.
      const double v = cover > 0 ? std::clamp(d.at(0, x, y) / cover / scale, -1.0, 1.0) : 0.0;
      const float t = static_cast<float>(std::sqrt(std::abs(v)));
      const Rgb hue = v >= 0 ? Rgb{1.0f, 0.45f, 0.12f} : Rgb{0.25f, 0.55f, 1.0f};
      const float p[3] = {hue.r * t * cover + kNoSurface.r * (1 - cover),
                          hue.g * t * cover + kNoSurface.g * (1 - cover),
                          hue.b * t * cover + kNoSurface.b * (1 - cover)};
      buf.setpixel(x, y, p, 3);
    }
  return buf;
}

// Up to kDefaultFrames frames of `frames`, first and last included, evenly spread.
std::vector<int> spread(const std::vector<int>& frames) {
  if (frames.size() <= static_cast<std::size_t>(kDefaultFrames)) return frames;
  std::vector<int> out;
  for (int k = 0; k < kDefaultFrames; ++k)
    out.push_back(frames[k * (frames.size() - 1) / (kDefaultFrames - 1)]);
  return out;
}

std::string number(const char* format, double v) {
  char text[32];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

}  // namespace

int run_preview(int argc, char** argv) {
  CommonOptions o = parse_common_options(kPreviewCommand, argc, argv, /*need_output=*/true);
  if (o.help) {
    print_help();
    return kExitOk;
  }
  install_log_handler(o.verbose, o.quiet);
  const ssgi::ThreadLimit threads(o.threads);
  if (!OIIO::Strutil::iends_with(o.run.output, ".png"))
    ssgi::throw_usage("output '" + o.run.output + "' must end in .png: the sheet is a PNG");
  std::error_code ec;
  if (fs::is_directory(o.run.output, ec))
    ssgi::throw_usage("output '" + o.run.output + "' is a directory");

  // Everything that can be refused is refused before the first frame is lit.
  ssgi::SequenceInfo seq = ssgi::open_sequence(o.run.input);
  if (o.run.input.frames.empty()) {
    o.run.input.frames = frame_ranges(spread(seq.frames));
    seq = ssgi::open_sequence(o.run.input);
  }
  const std::string first = seq.pattern.path_for(seq.frames.front());
  const std::string truth =
      o.truth.empty() ? "" : resolve_truth_layer(seq.channels, o.truth, first);
  std::optional<ssgi::SequencePattern> reference;
  if (!o.reference.empty()) reference = ssgi::parse_sequence_pattern(o.reference, nullptr);
  const ssgi::ColorManagement color = ssgi::color_management_for(o.run.gi.color, seq);
  const int w = seq.data_window.width(), h = seq.data_window.height();
  const int panel_w = std::min(w, kMaxPanelWidth);
  const int panel_h = std::max(1, static_cast<int>(std::lround(double(h) * panel_w / w)));

  std::vector<std::string> headers = {"direct", "indirect", "gi", "composite"};
  if (!truth.empty()) headers.push_back("indirect - " + o.truth);
  if (reference) headers.push_back("indirect - reference");
  std::vector<Row> rows;
  double truth_sum = 0;
  int truth_count = 0;
  ssgi::RunOptions run = o.run;
  run.output.clear();  // nothing written but the sheet
  ssgi::RunCallbacks callbacks;
  callbacks.on_result = [&](const ssgi::GBuffer& g, const ssgi::FrameResult& r) {
    Row row;
    row.frame = g.frame;
    // What the surfaces reflect of the direct light (and emit), the input beauty elsewhere.
    ssgi::Image direct = rgb_of(r.composite);
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x)
        for (int c = 0; c < 3 && g.is_surface(x, y); ++c) direct.at(c, x, y) -= r.gi.at(c, x, y);
    for (const ssgi::Image* light :
         std::initializer_list<const ssgi::Image*>{&direct, &r.indirect, &r.gi})
      row.panels.push_back({shrink(*light, panel_w, panel_h), {}, "", false});
    row.panels.push_back({shrink(rgb_of(r.composite), panel_w, panel_h), {}, "", false});
    const auto add_difference = [&](const ssgi::Image& against, const std::string& what) {
      const Difference d = difference(g, r.indirect, against);
      truth_sum += d.truth_mean;
      ++truth_count;
      row.panels.push_back({shrink(d.signed_mean, panel_w, panel_h),
                            shrink(d.surface, panel_w, panel_h),
                            "relRMSE " + number("%.3f", d.relrmse) + " against " + what, true});
    };
    if (!truth.empty()) {
      ssgi::Image t = read_layer(g.path, truth, g.data_window);
      color.input_to_working(&t);
      add_difference(t, o.truth);
    }
    if (reference) {
      const std::string path = reference->path_for(g.frame);
      add_difference(read_layer(path, "indirect", g.data_window), fs::path(path).filename());
    }
    rows.push_back(std::move(row));
  };
  const ssgi::RunReport report = ssgi::run_sequence(run, callbacks);
  for (const ssgi::FrameReport& f : report.frames)
    if (!f.ok) throw ssgi::Error(f.error_kind, f.error_file, f.error);

  // The differences share one scale: twice the truth's mean over the surfaces shown.
  const double scale = truth_count && truth_sum > 0 ? 2 * truth_sum / truth_count : 1;
  const int columns = static_cast<int>(headers.size());
  const bool captions = !truth.empty() || reference;
  const int row_h = panel_h + (captions ? kCaptionHeight : 0) + kGap;
  Canvas sheet(kLabelWidth + columns * (panel_w + kGap) + kGap,
               kTitleHeight + kHeaderHeight + static_cast<int>(rows.size()) * row_h + kGap,
               kBackground);
  sheet.text(kGap + 4, 10, "ssgi preview: " + fs::path(o.run.input.pattern).filename().string(), 18,
             kInk);
  std::string subtitle = "preset " + o.preset + ", display " + color.display() +
                         (color.view().empty() ? "" : " / " + color.view());
  if (captions)
    subtitle += "; difference red: ssgi brighter, blue: darker, full at +/-" +
                number("%.3g", scale) + " (2x the truth's mean)";
  sheet.text(kGap + 4, 32, subtitle, 13, kDim);
  for (int c = 0; c < columns; ++c)
    sheet.text(kLabelWidth + c * (panel_w + kGap) + panel_w / 2, kTitleHeight + kHeaderHeight / 2,
               headers[c], 15, kInk, Align::kCenter, Align::kCenter);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const int y = kTitleHeight + kHeaderHeight + static_cast<int>(r) * row_h;
    sheet.text(kLabelWidth - kGap, y + panel_h / 2, "frame " + std::to_string(rows[r].frame), 14,
               kInk, Align::kEnd, Align::kCenter);
    for (int c = 0; c < columns; ++c) {
      const Panel& p = rows[r].panels[c];
      const int x = kLabelWidth + c * (panel_w + kGap);
      sheet.paste(x, y,
                  p.difference ? difference_picture(p, scale) : light_picture(p.image, color));
      if (!p.caption.empty())
        sheet.text(x + panel_w / 2, y + panel_h + 4, p.caption, 12, kDim, Align::kCenter);
    }
  }
  sheet.write_png(o.run.output);
  ssgi::log_info(o.run.output + ": " + std::to_string(rows.size()) + " frames x " +
                 std::to_string(columns) + " passes");
  return kExitOk;
}

}  // namespace ssgi_cli
