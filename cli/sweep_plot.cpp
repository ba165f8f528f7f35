#include "sweep_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "draw.h"

namespace ssgi_cli {
namespace {

constexpr Rgb kWhite = {1, 1, 1}, kInk = {0.1f, 0.1f, 0.12f}, kGrey = {0.45f, 0.45f, 0.48f},
              kGridLine = {0.9f, 0.9f, 0.92f}, kFront = {0.12f, 0.35f, 0.75f},
              kDominated = {0.55f, 0.55f, 0.6f};

// The plot area, in pixels.
constexpr int kLeft = 120, kRight = kPlotWidth - 40, kTop = 100, kBottom = kPlotHeight - 120;

// A data axis mapped onto a pixel span, linear or logarithmic.
struct Axis {
  double lo = 0, hi = 1;  // data range (positive when log)
  bool log = false;
  int p0 = 0, p1 = 1;  // the pixels lo and hi map to

  double to_pixel(double v) const {
    const double t =
        log ? (std::log(v) - std::log(lo)) / (std::log(hi) - std::log(lo)) : (v - lo) / (hi - lo);
    return p0 + t * (p1 - p0);
  }
};

// A round step (1, 2 or 5 times a power of ten) giving about `count` intervals over the span.
double nice_step(double span, int count) {
  const double raw = span / count;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * power >= raw) return m * power;
  return 10 * power;
}

// A tick label: as many decimals as the step needs.
std::string tick_text(double v, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return text;
}

struct Tick {
  double value;
  std::string label;
};

// A linear axis over [lo, hi] padded by 8% each side, with round ticks.
std::vector<Tick> linear_axis(double lo, double hi, Axis* axis) {
  if (hi - lo < 1e-12 * std::max(1.0, std::abs(hi))) {
    const double half = std::max(std::abs(hi) * 0.05, 1e-3);
    lo -= half;
    hi += half;
  }
  const double pad = 0.08 * (hi - lo);
  axis->lo = lo - pad;
  axis->hi = hi + pad;
  axis->log = false;
  const double step = nice_step(axis->hi - axis->lo, 6);
  std::vector<Tick> ticks;
  for (double v = std::ceil(axis->lo / step) * step; v <= axis->hi + step * 1e-9; v += step)
    ticks.push_back({v, tick_text(v, step)});
  return ticks;
}

// A logarithmic axis over [lo, hi] padded by 15% each side, ticks at 1, 2, 5 x 10^k, or at
// every digit times 10^k when that gives fewer than 4.
std::vector<Tick> log_axis(double lo, double hi, Axis* axis) {
  axis->lo = lo / 1.15;
  axis->hi = hi * 1.15;
  axis->log = true;
  std::vector<Tick> ticks;
  for (const std::vector<double>& mantissas :
       {std::vector<double>{1, 2, 5}, std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
    ticks.clear();
    for (int k = static_cast<int>(std::floor(std::log10(axis->lo)));
         k <= static_cast<int>(std::ceil(std::log10(axis->hi))); ++k) {
      for (double m : mantissas) {
        const double v = m * std::pow(10.0, k);
        if (v >= axis->lo && v <= axis->hi) ticks.push_back({v, tick_text(v, std::pow(10.0, k))});
      }
    }
    if (ticks.size() >= 4) break;
  }
  return ticks;
}

struct Rect {
  int x0, y0, x1, y1;
  bool overlaps(const Rect& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
};

}  // namespace

std::vector<bool> pareto_front(const std::vector<PlotPoint>& points) {
  std::vector<bool> front(points.size(), true);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (std::size_t j = 0; j < points.size(); ++j) {
      const PlotPoint &a = points[i], &b = points[j];
      if (j != i && b.ms <= a.ms && b.error <= a.error && (b.ms < a.ms || b.error < a.error)) {
        front[i] = false;
        break;
      }
    }
  }
  return front;
}

void write_sweep_plot(const std::vector<PlotPoint>& points, const PlotText& text,
                      const std::string& path) {
  Canvas canvas(kPlotWidth, kPlotHeight, kWhite);
  double ms_lo = points.empty() ? 1 : points[0].ms, ms_hi = ms_lo;
  double e_lo = points.empty() ? 0 : points[0].error, e_hi = e_lo;
  for (const PlotPoint& p : points) {
    ms_lo = std::min(ms_lo, p.ms);
    ms_hi = std::max(ms_hi, p.ms);
    e_lo = std::min(e_lo, p.error);
    e_hi = std::max(e_hi, p.error);
  }
  Axis x{0, 1, false, kLeft, kRight}, y{0, 1, false, kBottom, kTop};
  const std::vector<Tick> x_ticks =
      ms_hi > 4 * ms_lo ? log_axis(ms_lo, ms_hi, &x) : linear_axis(ms_lo, ms_hi, &x);
  const std::vector<Tick> y_ticks = linear_axis(e_lo, e_hi, &y);

  // Grid lines and ticks, then the frame over them.
  for (const Tick& t : x_ticks) {
    const int px = static_cast<int>(std::lround(x.to_pixel(t.value)));
    canvas.line(px, kTop, px, kBottom, kGridLine);
    canvas.line(px, kBottom, px, kBottom + 6, kInk);
    canvas.text(px, kBottom + 12, t.label, 16, kInk, Align::kCenter, Align::kStart);
  }
  for (const Tick& t : y_ticks) {
    const int py = static_cast<int>(std::lround(y.to_pixel(t.value)));
    canvas.line(kLeft, py, kRight, py, kGridLine);
    canvas.line(kLeft - 6, py, kLeft, py, kInk);
    canvas.text(kLeft - 12, py, t.label, 16, kInk, Align::kEnd, Align::kCenter);
  }
  canvas.box(kLeft, kTop, kRight, kBottom, kInk, false);

  canvas.text(kLeft, 22, text.title, 26, kInk);
  canvas.text(kLeft, 60, text.subtitle, 16, kGrey);
  canvas.text((kLeft + kRight) / 2, kBottom + 44, text.x_title, 18, kInk, Align::kCenter);
  canvas.vertical_text(34, (kTop + kBottom) / 2, text.y_title, 18, kInk);
  canvas.text(kLeft, kPlotHeight - 36, text.footnote, 14, kGrey);

  // The front as a line through its points in order of time.
  const std::vector<bool> front = pareto_front(points);
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return points[a].ms < points[b].ms; });
  int last_x = -1, last_y = -1;
  for (std::size_t i : order) {
    if (!front[i]) continue;
    const int px = static_cast<int>(std::lround(x.to_pixel(points[i].ms)));
    const int py = static_cast<int>(std::lround(y.to_pixel(points[i].error)));
    if (last_x >= 0) canvas.line(last_x, last_y, px, py, kFront, 2);
    last_x = px;
    last_y = py;
  }

  // Markers, then the legend in the first inner corner that covers none (else top right),
  // then labels placed where they overlap no marker, label or the legend: right, left, above,
  // below the point, then further out.
  std::vector<Rect> taken;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double px = x.to_pixel(points[i].ms), py = y.to_pixel(points[i].error);
    if (front[i])
      canvas.disk(px, py, 6, kFront);
    else
      canvas.ring(px, py, 5.5, 2, kDominated);
    taken.push_back({static_cast<int>(px) - 7, static_cast<int>(py) - 7, static_cast<int>(px) + 8,
                     static_cast<int>(py) + 8});
  }
  {
    const std::string front_text = "Pareto front: no other run is both faster and closer";
    const std::string other_text = "another run is faster and closer";
    const int w =
        std::max(canvas.measure(front_text, 15).width, canvas.measure(other_text, 15).width) + 50;
    constexpr int kHeight = 58, kInset = 12;
    const Rect corners[] = {
        {kRight - kInset - w, kTop + kInset, kRight - kInset, kTop + kInset + kHeight},
        {kRight - kInset - w, kBottom - kInset - kHeight, kRight - kInset, kBottom - kInset},
        {kLeft + kInset, kTop + kInset, kLeft + kInset + w, kTop + kInset + kHeight},
        {kLeft + kInset, kBottom - kInset - kHeight, kLeft + kInset + w, kBottom - kInset},
    };
    Rect legend = corners[0];
    for (const Rect& r : corners) {
      if (std::none_of(taken.begin(), taken.end(), [&](const Rect& t) { return t.overlaps(r); })) {
        legend = r;
        break;
      }
    }
    canvas.box(legend.x0, legend.y0, legend.x1, legend.y1, kWhite, true);
    canvas.box(legend.x0, legend.y0, legend.x1, legend.y1, kGridLine, false);
    canvas.disk(legend.x0 + 20, legend.y0 + 18, 6, kFront);
    canvas.text(legend.x0 + 38, legend.y0 + 18, front_text, 15, kInk, Align::kStart,
                Align::kCenter);
    canvas.ring(legend.x0 + 20, legend.y0 + 41, 5.5, 2, kDominated);
    canvas.text(legend.x0 + 38, legend.y0 + 41, other_text, 15, kInk, Align::kStart,
                Align::kCenter);
    taken.push_back(legend);
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int px = static_cast<int>(std::lround(x.to_pixel(points[i].ms)));
    const int py = static_cast<int>(std::lround(y.to_pixel(points[i].error)));
    const TextExtent e = canvas.measure(points[i].label, 15);
    const int w = e.width, h = std::max(e.height, 15);
    Rect chosen{px + 10, py - h - 4, px + 10 + w, py - 4};
    bool placed = false;
    for (int reach : {10, 24, 40}) {
      const Rect candidates[] = {
          {px + reach, py - h / 2, px + reach + w, py + h - h / 2},
          {px - reach - w, py - h / 2, px - reach, py + h - h / 2},
          {px - w / 2, py - reach - h, px + w - w / 2, py - reach},
          {px - w / 2, py + reach, px + w - w / 2, py + reach + h},
          {px + reach, py - reach - h, px + reach + w, py - reach},
          {px + reach, py + reach, px + reach + w, py + reach + h},
      };
      for (const Rect& r : candidates) {
        if (r.x0 < kLeft + 2 || r.x1 > kRight - 2 || r.y0 < kTop + 2 || r.y1 > kBottom - 2)
          continue;
        if (std::any_of(taken.begin(), taken.end(), [&](const Rect& t) { return t.overlaps(r); }))
          continue;
        chosen = r;
        placed = true;
        break;
      }
      if (placed) break;
    }
    // On paper of its own, so that the front's line never runs through the letters.
    canvas.box(chosen.x0 - 2, chosen.y0 - 1, chosen.x1 + 1, chosen.y1 + 1, kWhite, true);
    canvas.text(chosen.x0, chosen.y0, points[i].label, 15, front[i] ? kFront : kInk);
    taken.push_back(chosen);
  }
  canvas.write_png(path);
}

}  // namespace ssgi_cli
