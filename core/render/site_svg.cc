#include "core/render/site_svg.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "core/localmap/pose_ops.h"
#include "core/render/svg_writer.h"

namespace lmd {
namespace {

// Pixel boxes already taken by labels and markers.
class LabelPlacer {
 public:
  void Reserve(double x0, double y0, double x1, double y1) { taken_.push_back({x0, y0, x1, y1}); }

  // A free place for a `width` x `height` px label near (x, y), trying rings
  // of growing radius; false if none.
  bool Place(double x, double y, double width, double height, double* left, double* baseline) {
    for (double radius : {9.0, 18.0, 30.0, 45.0}) {
      for (int k = 0; k < 12; ++k) {
        const double a = -M_PI / 4 + k * M_PI / 6;
        const double cx = x + radius * std::cos(a), cy = y - radius * std::sin(a);
        const Box box{cx - width / 2, cy - height / 2, cx + width / 2, cy + height / 2};
        if (std::any_of(taken_.begin(), taken_.end(), [&](const Box& t) { return Overlaps(box, t); })) continue;
        taken_.push_back(box);
        *left = box.x0;
        *baseline = box.y1 - height * 0.2;
        return true;
      }
    }
    return false;
  }

 private:
  struct Box {
    double x0, y0, x1, y1;
  };
  static bool Overlaps(const Box& a, const Box& b) {
    return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
  }
  std::vector<Box> taken_;
};

const char* FixColour(FixOutcome outcome) {
  switch (outcome) {
    case FixOutcome::kRight: return "#2ca02c";
    case FixOutcome::kWrong: return "#d62728";
    case FixOutcome::kUnsure: return "#ff7f0e";
  }
  return "black";
}

}  // namespace

std::string RenderSiteSvg(const SitePicture& picture, int* labels_left_out) {
  std::vector<Point2> walls;
  for (const SiteMap& m : picture.maps) {
    for (const Point2& p : m.map->points) walls.push_back(TransformPoint(m.anchor, p));
  }
  double min_x = std::numeric_limits<double>::max(), min_y = min_x;
  double max_x = std::numeric_limits<double>::lowest(), max_y = max_x;
  auto extend = [&](const Point2& p) {
    min_x = std::min(min_x, p.x), min_y = std::min(min_y, p.y);
    max_x = std::max(max_x, p.x), max_y = std::max(max_y, p.y);
  };
  for (const Point2& p : walls) extend(p);
  for (const Point2& p : picture.route) extend(p);
  for (const SiteFix& f : picture.fixes) extend({f.pose.x, f.pose.y});
  if (min_x > max_x) min_x = min_y = 0, max_x = max_y = 1;
  constexpr double kWidthPx = 1000, kTopPx = 64;  // the title and legend above the map
  const double top_m = kTopPx * (max_x - min_x + 2) / kWidthPx;
  SvgWriter svg(min_x - 1, min_y - 1, max_x + 1, max_y + 1 + top_m, kWidthPx);
  // Overlapping maps see each wall many times: one dot per 2 px cell.
  std::unordered_set<uint64_t> drawn;
  std::vector<Point2> dots;
  for (const Point2& p : walls) {
    const auto cx = static_cast<uint32_t>(svg.PxX(p.x) / 2), cy = static_cast<uint32_t>(svg.PxY(p.y) / 2);
    if (drawn.insert((static_cast<uint64_t>(cx) << 32) | cy).second) dots.push_back(p);
  }
  svg.Dots(dots, 0.9, "#aaaaaa");
  svg.Polyline(picture.route, {"#1f77b4", 1.5, "none", 0.8, ""});
  for (const std::vector<Point2>& region : picture.true_changes) {
    if (region.size() >= 3) svg.Polyline(region, {"#2ca02c", 1.5, "none", 1.0, ""}, /*closed=*/true);
  }

  LabelPlacer placer;
  placer.Reserve(0, 0, svg.width_px(), svg.PxY(max_y + 1));  // title and legend
  for (const Point2& c : picture.changes) {
    svg.Circle(c, 6.0, {"#d62728", 2.0, "none", 1.0, ""});
    placer.Reserve(svg.PxX(c.x) - 6, svg.PxY(c.y) - 6, svg.PxX(c.x) + 6, svg.PxY(c.y) + 6);
  }
  for (const SiteFix& f : picture.fixes) {
    const Point2 at{f.pose.x, f.pose.y};
    const std::string colour = FixColour(f.outcome);
    svg.Circle(at, 5.0, {colour, 2.0, colour, 0.8, ""});
    svg.Arrow(at, f.pose.theta, 1.2, {colour, 2.0, "none", 1.0, ""});
    placer.Reserve(svg.PxX(at.x) - 6, svg.PxY(at.y) - 6, svg.PxX(at.x) + 6, svg.PxY(at.y) + 6);
  }
  int left_out = 0;
  constexpr double kFontPx = 13.0;
  for (const SiteFix& f : picture.fixes) {
    if (f.label.empty()) continue;
    const double x = svg.PxX(f.pose.x), y = svg.PxY(f.pose.y);
    const double width = 0.62 * kFontPx * static_cast<double>(f.label.size()) + 4, height = kFontPx + 2;
    double left = 0, baseline = 0;
    if (!placer.Place(x, y, width, height, &left, &baseline)) {
      ++left_out;
      continue;
    }
    const double cx = left + width / 2, cy = baseline - height * 0.3;
    if (std::hypot(cx - x, cy - y) > 16) {
      svg.Raw("<line x1=\"" + std::to_string(x) + "\" y1=\"" + std::to_string(y) + "\" x2=\"" + std::to_string(cx) +
              "\" y2=\"" + std::to_string(cy) + "\" stroke=\"#666666\" stroke-width=\"0.8\"/>");
    }
    svg.TextPx(left + 2, baseline, f.label, kFontPx, FixColour(f.outcome));
  }
  svg.TextPx(10, 20, picture.title, 15.0);
  std::string legend = "grey: stored maps in the site frame";  // what the picture shows, only
  if (!picture.route.empty()) legend += "; blue: the robot's true route";
  if (!picture.changes.empty()) legend += "; red circles: changes found";
  if (!picture.true_changes.empty()) legend += "; green boxes: true changes";
  svg.TextPx(10, 38, legend, 11.0, "#444444");
  if (!picture.fixes.empty()) {
    svg.TextPx(10, 53, "fixes (arrow: heading, number: order): green right (0.2 m, 1 deg), red wrong, orange not sure",
               11.0, "#444444");
  }
  if (labels_left_out) *labels_left_out = left_out;
  return svg.ToString();
}

}  // namespace lmd
