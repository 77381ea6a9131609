#pragma once
// Plots a person can look at: 2D x–y maps (trajectories, features, walls) and time series,
// drawn with cairo into PNG files (written atomically).
#include <string>
#include <vector>

#include "geometry/pose2.hpp"
#include "plot/image.hpp"

namespace polarslam {

struct PlotSeries {
  std::string label;
  std::vector<Vec2> points;
  Rgb color{0, 0, 0};
  double line_width = 1.5;   ///< px; 0 = markers only
  double marker_radius = 0;  ///< px; 0 = no markers
};

struct PlotSegment {
  Vec2 a, b;
  Rgb color{0, 0, 0};
  double width = 1.0;
};

struct PlotEllipse {
  Vec2 center;
  Mat2 cov;      ///< drawn at `sigma` standard deviations
  double sigma = 2.0;
  Rgb color{200, 0, 0};
};

struct Plot {
  std::string title, x_label = "x [m]", y_label = "y [m]";
  bool equal_axes = true;   ///< metric maps: same scale on both axes
  int width = 1000, height = 800;
  std::vector<PlotSeries> series;
  std::vector<PlotSegment> segments;
  std::vector<PlotEllipse> ellipses;
  /// Optional raster drawn under everything, spanning `image_min`..`image_max` in data units.
  RgbImage background;
  Vec2 image_min = Vec2::Zero(), image_max = Vec2::Zero();
};

/// Renders the plot into a PNG. Throws std::runtime_error naming the file on failure.
void writePlotPng(const std::string& path, const Plot& plot);

/// Distinct colours for series.
Rgb seriesColor(int index);

}  // namespace polarslam
