#include "core/render/result_svg.h"

#include <algorithm>
#include <limits>

#include "core/align/relative_pose.h"
#include "core/render/svg_writer.h"

namespace lmd {

std::string RenderResultSvg(const ResultPicture& picture) {
  std::vector<Point2> query_points;  // in the db frame
  for (const Point2& p : picture.query->points) query_points.push_back(TransformPoint(picture.query_in_db, p));
  double min_x = std::numeric_limits<double>::max(), min_y = min_x;
  double max_x = std::numeric_limits<double>::lowest(), max_y = max_x;
  for (const std::vector<Point2>* points : {&picture.db->points, static_cast<const std::vector<Point2>*>(&query_points)}) {
    for (const Point2& p : *points) {
      min_x = std::min(min_x, p.x);
      min_y = std::min(min_y, p.y);
      max_x = std::max(max_x, p.x);
      max_y = std::max(max_y, p.y);
    }
  }
  SvgWriter svg(min_x - 1, min_y - 1, max_x + 1, max_y + 1, 800);
  svg.Dots(picture.db->points, 1.6, "#999999");
  svg.Dots(query_points, 1.2, "#1f77b4");
  if (picture.true_change.size() >= 3) {
    std::vector<Point2> region;
    for (const Point2& p : picture.true_change) region.push_back(TransformPoint(picture.query_in_db, p));
    svg.Polyline(region, {"#2ca02c", 2.0, "none", 1.0, ""}, /*closed=*/true);
  }
  // One circle per mask point, one rank label per mask (above its highest
  // point: a label per point stacked them on top of each other).
  for (size_t rank = 0; rank < picture.masks.size(); ++rank) {
    if (picture.masks[rank].empty()) continue;
    Point2 top{0, std::numeric_limits<double>::lowest()};
    for (const Point2& p : picture.masks[rank]) {
      const Point2 at = TransformPoint(picture.query_in_db, p);
      svg.Circle(at, 7.0, {"#d62728", 2.0, "none", 1.0, ""});
      if (at.y > top.y) top = at;
    }
    svg.TextPx(svg.PxX(top.x) + 8, svg.PxY(top.y) - 8, std::to_string(rank + 1), 12.0, "#d62728");
  }
  svg.TextPx(10, 20, picture.title, 14.0);
  svg.TextPx(10, 38, "grey: stored map   blue: query map (aligned)   red: change masks (rank)   green: true change",
             11.0, "#444444");
  return svg.ToString();
}

}  // namespace lmd
