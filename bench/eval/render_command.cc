// lmd-eval render: an SVG picture of one local map (paper Fig. 1b / Fig. 4):
// occupancy grid, wall primitives, room cells, trajectory, CoG and CoR
// viewpoints, and the features of the descriptor in the planned frame.
#include <cstdio>
#include <string>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/data_paths.h"
#include "core/describe/describer.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/render/local_map_svg.h"
#include "core/render/svg_writer.h"
#include "core/sim/simulate.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd::eval {

int RunRender(int argc, char** argv) {
  Flags args({"log", "map", "out"}, {"demo", "cog"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval render: %s\n", args.error().c_str());
    return 2;
  }
  const std::string out = args.Get("out");
  if (out.empty() || (!args.Has("log") && !args.Has("demo"))) {
    std::fprintf(stderr, "usage: lmd-eval render (--log FILE | --demo) [--map INDEX] [--cog] --out FILE.svg\n");
    return 2;
  }
  LaserLog log;
  std::string name = "demo";
  if (args.Has("log")) {
    Result<LaserLog> read = ReadCarmenLog(args.Get("log"));
    if (!read.ok()) {
      std::fprintf(stderr, "lmd-eval render: %s\n", read.status().ToString().c_str());
      return 1;
    }
    log = std::move(read.value());
    name = DatasetName(args.Get("log"));
  } else {
    log = DefaultDemoLog();
  }
  LocalMapOptions lm;
  lm.id_prefix = name;
  const std::vector<LocalMap> maps = BuildLocalMaps(log, lm);
  uint64_t index = 0;
  if (maps.empty() || !args.Count("map", 0, maps.size() - 1, 0, &index)) {
    std::fprintf(stderr, "lmd-eval render: --map must be in [0, %zu)\n", maps.size());
    return 2;
  }
  const LocalMap& map = maps[static_cast<size_t>(index)];
  ViewpointOptions vo;
  if (args.Has("cog")) vo.planner = Planner::kCoG;
  const ViewpointPlan plan = PlanViewpointDetailed(map, vo);
  const Lmd lmd = Describe(map, plan.frame);
  LocalMapSvgOptions so;
  so.title = name + " map " + std::to_string(index) + ": " + std::to_string(map.points.size()) + " points, " +
             std::to_string(lmd.features.size()) + " features, planner " + PlannerName(vo.planner);
  const std::string svg = RenderLocalMapSvg(map, plan, &lmd, so);
  std::FILE* f = std::fopen(out.c_str(), "wb");
  if (f == nullptr || std::fwrite(svg.data(), 1, svg.size(), f) != svg.size()) {
    std::fprintf(stderr, "lmd-eval render: cannot write %s\n", out.c_str());
    if (f) std::fclose(f);
    return 1;
  }
  std::fclose(f);
  std::printf("wrote %s (%s map %ld)\n", out.c_str(), name.c_str(), index);
  return 0;
}

}  // namespace lmd::eval
