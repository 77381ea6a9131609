#include "plot/plot.hpp"

#include <Eigen/Eigenvalues>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace polarslam {
namespace {

struct Bounds {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  void add(const Vec2& p) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return;
    x0 = std::min(x0, p.x()); x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y()); y1 = std::max(y1, p.y());
  }
  bool valid() const { return x0 <= x1 && y0 <= y1; }
};

Bounds dataBounds(const Plot& plot) {
  Bounds b;
  for (const auto& s : plot.series)
    for (const auto& p : s.points) b.add(p);
  for (const auto& s : plot.segments) { b.add(s.a); b.add(s.b); }
  for (const auto& e : plot.ellipses) b.add(e.center);
  if (plot.background.width > 0) { b.add(plot.image_min); b.add(plot.image_max); }
  if (!b.valid()) b = Bounds{0, 0, 1, 1};
  const double pad_x = std::max(1e-3, 0.05 * (b.x1 - b.x0)), pad_y = std::max(1e-3, 0.05 * (b.y1 - b.y0));
  b.x0 -= pad_x; b.x1 += pad_x; b.y0 -= pad_y; b.y1 += pad_y;
  return b;
}

/// Maps data coordinates into the plot area (pixels), y up.
struct Frame {
  double left, top, width, height;
  Bounds b;
  double sx, sy;
  Frame(const Plot& plot, Bounds bounds) : left(80), top(50), b(bounds) {
    width = plot.width - left - 30;
    height = plot.height - top - 70;
    sx = width / (b.x1 - b.x0);
    sy = height / (b.y1 - b.y0);
    if (plot.equal_axes) {
      const double s = std::min(sx, sy);
      sx = sy = s;
    }
  }
  double px(double x) const { return left + (x - b.x0) * sx; }
  double py(double y) const { return top + height - (y - b.y0) * sy; }
  double dataRight() const { return b.x0 + width / sx; }
  double dataTop() const { return b.y0 + height / sy; }
};

void setColor(cairo_t* cr, Rgb c, double alpha = 1.0) { cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, alpha); }

double niceStep(double span) {
  const double raw = span / 8.0, mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) return m * mag;
  return 10.0 * mag;
}

void drawText(cairo_t* cr, double x, double y, const std::string& text, double size, double align = 0.0) {
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, text.c_str(), &ext);
  cairo_move_to(cr, x - align * ext.width, y);
  cairo_show_text(cr, text.c_str());
}

void drawAxes(cairo_t* cr, const Plot& plot, const Frame& f) {
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, f.left, f.top, f.width, f.height);
  cairo_stroke(cr);
  char label[32];
  const double step_x = niceStep(f.dataRight() - f.b.x0), step_y = niceStep(f.dataTop() - f.b.y0);
  for (double x = std::ceil(f.b.x0 / step_x) * step_x; x <= f.dataRight(); x += step_x) {
    cairo_set_source_rgba(cr, 0, 0, 0, 0.08);
    cairo_move_to(cr, f.px(x), f.top); cairo_line_to(cr, f.px(x), f.top + f.height); cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    std::snprintf(label, sizeof(label), "%g", std::abs(x) < 1e-12 ? 0.0 : x);
    drawText(cr, f.px(x), f.top + f.height + 18, label, 12, 0.5);
  }
  for (double y = std::ceil(f.b.y0 / step_y) * step_y; y <= f.dataTop(); y += step_y) {
    cairo_set_source_rgba(cr, 0, 0, 0, 0.08);
    cairo_move_to(cr, f.left, f.py(y)); cairo_line_to(cr, f.left + f.width, f.py(y)); cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    std::snprintf(label, sizeof(label), "%g", std::abs(y) < 1e-12 ? 0.0 : y);
    drawText(cr, f.left - 6, f.py(y) + 4, label, 12, 1.0);
  }
  drawText(cr, f.left + f.width / 2, plot.height - 25, plot.x_label, 14, 0.5);
  cairo_save(cr);
  cairo_translate(cr, 22, f.top + f.height / 2);
  cairo_rotate(cr, -M_PI / 2);
  drawText(cr, 0, 0, plot.y_label, 14, 0.5);
  cairo_restore(cr);
  drawText(cr, plot.width / 2.0, 30, plot.title, 18, 0.5);
}

void drawBackground(cairo_t* cr, const Plot& plot, const Frame& f) {
  const RgbImage& img = plot.background;
  if (img.width <= 0 || img.height <= 0) return;
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, img.width, img.height);
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Rgb c = img.at(x, y);
      auto* px = reinterpret_cast<uint32_t*>(data + y * stride) + x;
      *px = (uint32_t{c.r} << 16) | (uint32_t{c.g} << 8) | c.b;
    }
  cairo_surface_mark_dirty(surface);
  cairo_save(cr);
  const double x0 = f.px(plot.image_min.x()), y0 = f.py(plot.image_max.y());
  const double w = f.px(plot.image_max.x()) - x0, h = f.py(plot.image_min.y()) - y0;
  cairo_rectangle(cr, f.left, f.top, f.width, f.height);
  cairo_clip(cr);
  cairo_translate(cr, x0, y0);
  cairo_scale(cr, w / img.width, h / img.height);
  cairo_set_source_surface(cr, surface, 0, 0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(surface);
}

void drawData(cairo_t* cr, const Plot& plot, const Frame& f) {
  cairo_save(cr);
  cairo_rectangle(cr, f.left, f.top, f.width, f.height);
  cairo_clip(cr);
  for (const auto& s : plot.segments) {
    setColor(cr, s.color);
    cairo_set_line_width(cr, s.width);
    cairo_move_to(cr, f.px(s.a.x()), f.py(s.a.y()));
    cairo_line_to(cr, f.px(s.b.x()), f.py(s.b.y()));
    cairo_stroke(cr);
  }
  for (const auto& e : plot.ellipses) {
    Eigen::SelfAdjointEigenSolver<Mat2> eig(e.cov);
    if (eig.info() != Eigen::Success) continue;
    const Vec2 ev = eig.eigenvalues().cwiseMax(0.0);
    const Vec2 major = eig.eigenvectors().col(1);
    setColor(cr, e.color, 0.8);
    cairo_set_line_width(cr, 1.0);
    for (int i = 0; i <= 48; ++i) {
      const double t = 2.0 * M_PI * i / 48;
      const Vec2 local(std::sqrt(ev(1)) * std::cos(t), std::sqrt(ev(0)) * std::sin(t));
      const Vec2 minor(-major.y(), major.x());
      const Vec2 p = e.center + e.sigma * (local.x() * major + local.y() * minor);
      (i == 0 ? cairo_move_to : cairo_line_to)(cr, f.px(p.x()), f.py(p.y()));
    }
    cairo_stroke(cr);
  }
  for (const auto& s : plot.series) {
    setColor(cr, s.color);
    if (s.line_width > 0 && s.points.size() > 1) {
      cairo_set_line_width(cr, s.line_width);
      bool pen_down = false;
      for (const auto& p : s.points) {
        if (!std::isfinite(p.x()) || !std::isfinite(p.y())) { pen_down = false; continue; }
        (pen_down ? cairo_line_to : cairo_move_to)(cr, f.px(p.x()), f.py(p.y()));
        pen_down = true;
      }
      cairo_stroke(cr);
    }
    if (s.marker_radius > 0)
      for (const auto& p : s.points) {
        cairo_arc(cr, f.px(p.x()), f.py(p.y()), s.marker_radius, 0, 2 * M_PI);
        cairo_fill(cr);
      }
  }
  cairo_restore(cr);
}

void drawLegend(cairo_t* cr, const Plot& plot, const Frame& f) {
  double y = f.top + 18;
  for (const auto& s : plot.series) {
    if (s.label.empty()) continue;
    setColor(cr, s.color);
    cairo_rectangle(cr, f.left + 10, y - 9, 18, 8);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    drawText(cr, f.left + 34, y, s.label, 13);
    y += 18;
  }
}

}  // namespace

Rgb seriesColor(int index) {
  static const Rgb palette[] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {255, 127, 14},
                                {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {127, 127, 127}};
  return palette[static_cast<size_t>(index) % 8];
}

void writePlotPng(const std::string& path, const Plot& plot) {
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, plot.width, plot.height);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  const Frame frame(plot, dataBounds(plot));
  drawBackground(cr, plot, frame);
  drawAxes(cr, plot, frame);
  drawData(cr, plot, frame);
  drawLegend(cr, plot, frame);
  cairo_destroy(cr);
  const std::string tmp = path + ".tmp";
  const cairo_status_t status = cairo_surface_write_to_png(surface, tmp.c_str());
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS) throw std::runtime_error("cannot write plot '" + path + "'");
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("cannot rename plot to '" + path + "': " + ec.message());
}

}  // namespace polarslam
