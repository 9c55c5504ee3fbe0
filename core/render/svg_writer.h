// A tiny SVG builder for maps and plots. World coordinates (m, y up) are
// mapped to SVG pixels (y down) through a fixed view box set at construction;
// shapes are appended in drawing order. Colours and styles are plain SVG
// strings ("#1f77b4", "none", "red").
#pragma once

#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"

namespace lmd {

struct SvgStyle {
  std::string stroke = "black";
  double stroke_width_px = 1.0;  // px, independent of zoom
  std::string fill = "none";
  double opacity = 1.0;          // 0..1
  std::string dash;              // SVG stroke-dasharray, e.g. "4 2"; empty = solid
};

class SvgWriter {
 public:
  // View box [min_x, max_x] x [min_y, max_y] (world, m) drawn into a picture
  // `width_px` wide (height follows the aspect ratio). A degenerate box is
  // widened to 1 m.
  SvgWriter(double min_x, double min_y, double max_x, double max_y, double width_px = 800.0);

  double width_px() const { return width_px_; }
  double height_px() const { return height_px_; }
  // World -> pixel coordinates.
  double PxX(double x) const;
  double PxY(double y) const;

  void Line(const Point2& a, const Point2& b, const SvgStyle& style);
  void Polyline(const std::vector<Point2>& points, const SvgStyle& style, bool closed = false);
  // Circle of radius_px pixels (markers) centred at a world point.
  void Circle(const Point2& centre, double radius_px, const SvgStyle& style);
  // Axis-aligned world rectangle, or any quadrilateral via Polyline(closed).
  void Rect(double x0, double y0, double x1, double y1, const SvgStyle& style);
  // Many small same-style squares (e.g. grid cells or points) as ONE path
  // element: squares of side side_m (world) centred at the given points.
  void Squares(const std::vector<Point2>& centres, double side_m, const SvgStyle& style);
  // Many dots of radius_px as one path.
  void Dots(const std::vector<Point2>& centres, double radius_px, const std::string& colour);
  // Text at a world point, font size in px; anchor "start" / "middle" / "end".
  void Text(const Point2& at, const std::string& text, double size_px = 12.0,
            const std::string& colour = "black", const std::string& anchor = "start");
  // Text at pixel coordinates (titles, legends).
  void TextPx(double x_px, double y_px, const std::string& text, double size_px = 12.0,
              const std::string& colour = "black", const std::string& anchor = "start");
  // Arrow from a (world) in direction `angle` (rad), length_m long.
  void Arrow(const Point2& a, double angle, double length_m, const SvgStyle& style);
  // Raw SVG element (already in pixel coordinates), for anything else.
  void Raw(const std::string& element);

  // The complete document.
  std::string ToString() const;
  // Writes ToString() to path; IoError on failure.
  Status Save(const std::string& path) const;

 private:
  double min_x_, min_y_, max_x_, max_y_;
  double width_px_, height_px_, scale_;
  std::string body_;
};

// Escapes &, <, >, " for SVG text and attributes.
std::string SvgEscape(const std::string& text);

}  // namespace lmd
