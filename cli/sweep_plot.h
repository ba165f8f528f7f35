// The picture of `ssgi sweep`: error against time per frame, every run a labelled point, the
// Pareto front drawn through the runs no other run beats on both.
#pragma once

#include <string>
#include <vector>

namespace ssgi_cli {

// One run in the plot.
struct PlotPoint {
  std::string label;
  double ms = 0;     // x: time per frame, positive
  double error = 0;  // y: a finite error, smaller is better
};

// The words around the points.
struct PlotText {
  std::string title, subtitle, x_title, y_title, footnote;
};

constexpr int kPlotWidth = 1200, kPlotHeight = 800;

// For each point, whether it is on the Pareto front: no other point is at most as slow and at
// most as wrong, and better in one of the two.
std::vector<bool> pareto_front(const std::vector<PlotPoint>& points);

// Draws the plot (kPlotWidth x kPlotHeight; x on a log scale when the times span more than a
// factor of 4) and writes it as PNG atomically. Throws Error(kIO).
void write_sweep_plot(const std::vector<PlotPoint>& points, const PlotText& text,
                      const std::string& path);

}  // namespace ssgi_cli
