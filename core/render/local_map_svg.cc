#include "core/render/local_map_svg.h"

#include <algorithm>
#include <cmath>

#include "core/render/svg_writer.h"

namespace lmd {

std::string RenderLocalMapSvg(const LocalMap& map, const ViewpointPlan& plan, const Lmd* lmd,
                              const LocalMapSvgOptions& options) {
  const OccupancyGrid& grid = plan.grid;
  // View box: the grid's corners in the own frame.
  double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
  for (int cx : {0, 1}) {
    for (int cy : {0, 1}) {
      const Point2 c = grid.ToOwn({grid.min_x() + cx * grid.width() * grid.cell_m(),
                                   grid.min_y() + cy * grid.height() * grid.cell_m()});
      lo_x = std::min(lo_x, c.x), hi_x = std::max(hi_x, c.x);
      lo_y = std::min(lo_y, c.y), hi_y = std::max(hi_y, c.y);
    }
  }
  const double top_m = 0.06 * (hi_x - lo_x);  // room for the title and legend
  SvgWriter svg(lo_x, lo_y, hi_x, hi_y + top_m, options.width_px);
  const double cell = grid.cell_m();
  const double side = cell * 1.05;
  const SvgStyle none{"none", 0, "", 1, ""};
  auto filled = [&](const std::string& colour, double opacity) { return SvgStyle{"none", 0, colour, opacity, ""}; };

  if (options.grid) {
    std::vector<Point2> free_cells, occupied;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        const CellState s = grid.at(x, y);
        if (s == CellState::kFree) free_cells.push_back(grid.CellCentre(x, y));
        if (s == CellState::kOccupied) occupied.push_back(grid.CellCentre(x, y));
      }
    }
    // Unknown = background grey, free = white, occupied = dark.
    svg.Rect(lo_x, lo_y, hi_x, hi_y, filled("#d9d9d9", 1.0));
    svg.Squares(free_cells, side, filled("#ffffff", 1.0));
    svg.Squares(occupied, side, filled("#404040", 1.0));
  }
  if (options.rooms && plan.room_cells.size() == grid.cells().size()) {
    std::vector<Point2> room, peak;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        const size_t i = static_cast<size_t>(y) * grid.width() + x;
        if (plan.room_peak.size() == plan.room_cells.size() && plan.room_peak[i]) {
          peak.push_back(grid.CellCentre(x, y));
        } else if (plan.room_cells[i]) {
          room.push_back(grid.CellCentre(x, y));
        }
      }
    }
    svg.Squares(room, side, filled("#9ecae1", 0.45));
    svg.Squares(peak, side, filled("#ff7f0e", 0.6));
  }
  if (options.walls) {
    for (const WallPrimitive& w : plan.walls) {
      const Point2 a = grid.CellCentre(w.x0, w.y0), b = grid.CellCentre(w.x1, w.y1);
      svg.Line(a, b, SvgStyle{w.horizontal ? "#d62728" : "#2ca02c", 2.0, "none", 0.85, ""});
    }
  }
  std::vector<Point2> traj;
  for (const Pose2& p : map.trajectory) traj.push_back({p.x, p.y});
  svg.Polyline(traj, SvgStyle{"#1f77b4", 2.5, "none", 1.0, ""});
  if (!traj.empty()) svg.Circle(traj.front(), 4, SvgStyle{"#1f77b4", 1, "#1f77b4", 1, ""});

  if (options.features && lmd != nullptr) {
    std::vector<Point2> feats;
    for (const Feature& f : lmd->features) feats.push_back(FromFrame(lmd->frame, {f.x, f.y}));
    svg.Dots(feats, 2.5, "#9467bd");
  }
  // Viewpoints: CoG (red diamond-ish circle), CoR (orange), axes of the chosen frame.
  const bool cor_chosen = std::hypot(plan.frame.origin.x - plan.cor.origin.x, plan.frame.origin.y - plan.cor.origin.y) < 1e-12;
  const double axis_m = std::max(0.8, 0.05 * (hi_x - lo_x));
  svg.Arrow(plan.frame.origin, plan.frame.heading, axis_m, SvgStyle{"black", 2.0, "none", 1, ""});
  svg.Arrow(plan.frame.origin, plan.frame.heading + M_PI / 2, axis_m * 0.6, SvgStyle{"black", 1.5, "none", 1, ""});
  svg.Circle(plan.cog.origin, cor_chosen ? 6 : 9, SvgStyle{"black", 1.5, "#d62728", 1, ""});
  svg.Circle(plan.cor.origin, cor_chosen ? 9 : 6, SvgStyle{"black", 1.5, "#ff7f0e", 1, ""});
  svg.Text(plan.cog.origin, "  CoG", 13, "#d62728");
  svg.Text(plan.cor.origin, "  CoR", 13, "#ff7f0e");

  const std::string title = options.title.empty() ? "local map " + map.id : options.title;
  svg.TextPx(8, 18, title, 15);
  svg.TextPx(svg.width_px() - 8, 18,
             "grid free/occupied/unknown = white/dark/grey; walls red(x)/green(y); rooms blue; 90% peak orange; "
             "trajectory blue; features purple",
             10, "#333333", "end");
  (void)none;
  return svg.ToString();
}

}  // namespace lmd
