#include "core/render/svg_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace lmd {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", std::isfinite(v) ? v : 0.0);
  return buf;
}

std::string StyleAttrs(const SvgStyle& s) {
  std::string a = " stroke=\"" + SvgEscape(s.stroke) + "\" stroke-width=\"" + Num(s.stroke_width_px) +
                  "\" fill=\"" + SvgEscape(s.fill) + "\"";
  if (s.opacity < 1.0) a += " opacity=\"" + Num(s.opacity) + "\"";
  if (!s.dash.empty()) a += " stroke-dasharray=\"" + SvgEscape(s.dash) + "\"";
  return a;
}

}  // namespace

std::string SvgEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

SvgWriter::SvgWriter(double min_x, double min_y, double max_x, double max_y, double width_px)
    : min_x_(min_x), min_y_(min_y), max_x_(max_x), max_y_(max_y), width_px_(width_px > 0 ? width_px : 800.0) {
  if (!(max_x_ - min_x_ > 1e-9)) max_x_ = min_x_ + 1.0;
  if (!(max_y_ - min_y_ > 1e-9)) max_y_ = min_y_ + 1.0;
  scale_ = width_px_ / (max_x_ - min_x_);
  height_px_ = (max_y_ - min_y_) * scale_;
}

double SvgWriter::PxX(double x) const { return (x - min_x_) * scale_; }
double SvgWriter::PxY(double y) const { return (max_y_ - y) * scale_; }

void SvgWriter::Line(const Point2& a, const Point2& b, const SvgStyle& style) {
  body_ += "<line x1=\"" + Num(PxX(a.x)) + "\" y1=\"" + Num(PxY(a.y)) + "\" x2=\"" + Num(PxX(b.x)) + "\" y2=\"" +
           Num(PxY(b.y)) + "\"" + StyleAttrs(style) + "/>\n";
}

void SvgWriter::Polyline(const std::vector<Point2>& points, const SvgStyle& style, bool closed) {
  if (points.empty()) return;
  body_ += closed ? "<polygon points=\"" : "<polyline points=\"";
  for (const Point2& p : points) body_ += Num(PxX(p.x)) + "," + Num(PxY(p.y)) + " ";
  body_ += "\"" + StyleAttrs(style) + "/>\n";
}

void SvgWriter::Circle(const Point2& c, double radius_px, const SvgStyle& style) {
  body_ += "<circle cx=\"" + Num(PxX(c.x)) + "\" cy=\"" + Num(PxY(c.y)) + "\" r=\"" + Num(radius_px) + "\"" +
           StyleAttrs(style) + "/>\n";
}

void SvgWriter::Rect(double x0, double y0, double x1, double y1, const SvgStyle& style) {
  const double px = PxX(std::min(x0, x1)), py = PxY(std::max(y0, y1));
  body_ += "<rect x=\"" + Num(px) + "\" y=\"" + Num(py) + "\" width=\"" + Num(std::abs(x1 - x0) * scale_) +
           "\" height=\"" + Num(std::abs(y1 - y0) * scale_) + "\"" + StyleAttrs(style) + "/>\n";
}

void SvgWriter::Squares(const std::vector<Point2>& centres, double side_m, const SvgStyle& style) {
  if (centres.empty()) return;
  const double s = side_m * scale_;
  body_ += "<path d=\"";
  for (const Point2& c : centres) {
    body_ += "M" + Num(PxX(c.x) - s / 2) + " " + Num(PxY(c.y) - s / 2) + "h" + Num(s) + "v" + Num(s) + "h" +
             Num(-s) + "z";
  }
  SvgStyle st = style;
  body_ += "\"" + StyleAttrs(st) + "/>\n";
}

void SvgWriter::Dots(const std::vector<Point2>& centres, double radius_px, const std::string& colour) {
  if (centres.empty()) return;
  body_ += "<path d=\"";
  for (const Point2& c : centres) {
    body_ += "M" + Num(PxX(c.x) - radius_px) + " " + Num(PxY(c.y)) + "a" + Num(radius_px) + " " + Num(radius_px) +
             " 0 1 0 " + Num(2 * radius_px) + " 0a" + Num(radius_px) + " " + Num(radius_px) + " 0 1 0 " +
             Num(-2 * radius_px) + " 0";
  }
  body_ += "\" fill=\"" + SvgEscape(colour) + "\" stroke=\"none\"/>\n";
}

void SvgWriter::Text(const Point2& at, const std::string& text, double size_px, const std::string& colour,
                     const std::string& anchor) {
  TextPx(PxX(at.x), PxY(at.y), text, size_px, colour, anchor);
}

void SvgWriter::TextPx(double x, double y, const std::string& text, double size_px, const std::string& colour,
                       const std::string& anchor) {
  body_ += "<text x=\"" + Num(x) + "\" y=\"" + Num(y) + "\" font-family=\"sans-serif\" font-size=\"" + Num(size_px) +
           "\" fill=\"" + SvgEscape(colour) + "\" text-anchor=\"" + SvgEscape(anchor) + "\">" + SvgEscape(text) +
           "</text>\n";
}

void SvgWriter::Arrow(const Point2& a, double angle, double length_m, const SvgStyle& style) {
  const Point2 b{a.x + length_m * std::cos(angle), a.y + length_m * std::sin(angle)};
  Line(a, b, style);
  const double head = 0.25 * length_m;
  for (double side : {+1.0, -1.0}) {
    const double t = angle + M_PI + side * 0.45;
    Line(b, {b.x + head * std::cos(t), b.y + head * std::sin(t)}, style);
  }
}

void SvgWriter::Raw(const std::string& element) { body_ += element + "\n"; }

std::string SvgWriter::ToString() const {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + Num(width_px_) + "\" height=\"" + Num(height_px_) +
         "\" viewBox=\"0 0 " + Num(width_px_) + " " + Num(height_px_) + "\">\n<rect width=\"100%\" height=\"100%\" "
         "fill=\"white\"/>\n" + body_ + "</svg>\n";
}

Status SvgWriter::Save(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out) return Status::IoError("cannot open " + path + " for writing");
  out << ToString();
  out.close();
  if (!out) return Status::IoError("cannot write " + path);
  return Status::Ok();
}

}  // namespace lmd
