// lmd-eval export: the local maps of a log and the ground truth of the
// protocol in plain text, so that other tools can be run on exactly the same
// maps. Format (documented in the files' headers too):
//
// DIR/<name>.maps.txt
//   # comment lines
//   MAP <index> <id> <n_points> <n_poses> <travel_start_m> <travel_end_m> <gx> <gy> <gtheta>
//   P <x> <y>                 n_points lines: points, map's own frame (m)
//   T <x> <y> <theta>         n_poses lines: trajectory, own frame (m, rad)
//   (gx, gy, gtheta) = pose of the map's own frame in the log's frame: ground
//   truth only, a method must not read it.
// DIR/<name>.truth.txt
//   PAIR <query> <relevant> <mean_dist_m> <candidates>   one per counted query (paper's scoring)
//   PLACE <query> <map> ...                              candidates showing the query's place (overlap >= 0.5)
//   Candidates of a query: maps whose travel_start differs by more than 10 m.
#include <cstdio>
#include <filesystem>
#include <string>

#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/data_paths.h"
#include "bench/eval/eval_dataset.h"

namespace lmd::eval {

int RunExport(int argc, char** argv) {
  Flags args(WithSensorFlags({"log", "out"}));
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval export: %s\n", args.error().c_str());
    return 2;
  }
  std::vector<std::string> logs = args.GetAll("log");
  const std::string out = args.Get("out");
  DatasetOptions sensor;
  if (!SensorFromFlags(args, &sensor)) {
    std::fprintf(stderr, "lmd-eval export: %s\n", args.error().c_str());
    return 2;
  }
  if (logs.empty() || out.empty()) {
    std::fprintf(stderr, "usage: lmd-eval export --log FILE... --out DIR [sensor flags]\n");
    return 2;
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  for (const std::string& log : logs) {
    Result<Dataset> d = LoadDataset(log, sensor);
    if (!d.ok()) {
      std::fprintf(stderr, "lmd-eval export: %s\n", d.status().ToString().c_str());
      return 1;
    }
    const std::string maps_path = (std::filesystem::path(out) / (d->name + ".maps.txt")).string();
    const std::string truth_path = (std::filesystem::path(out) / (d->name + ".truth.txt")).string();
    std::FILE* f = std::fopen(maps_path.c_str(), "w");
    std::FILE* t = std::fopen(truth_path.c_str(), "w");
    if (!f || !t) {
      std::fprintf(stderr, "lmd-eval export: cannot write into %s\n", out.c_str());
      if (f) std::fclose(f);
      if (t) std::fclose(t);
      return 1;
    }
    std::fprintf(f,
                 "# lmd local maps v1 from %s: 5 m of travel every 1 m, own frame = first pose\n"
                 "# MAP index id n_points n_poses travel_start_m travel_end_m gx gy gtheta (ground truth only)\n"
                 "# P x y (own frame, m); T x y theta (trajectory, own frame)\n",
                 log.c_str());
    for (size_t i = 0; i < d->maps.size(); ++i) {
      const LocalMap& m = d->maps[i];
      std::fprintf(f, "MAP %zu %s %zu %zu %.4f %.4f %.6f %.6f %.8f\n", i, m.id.c_str(), m.points.size(),
                   m.trajectory.size(), m.truth.travel_start, m.truth.travel_end, m.truth.global_frame.x,
                   m.truth.global_frame.y, m.truth.global_frame.theta);
      for (const Point2& p : m.points) std::fprintf(f, "P %.4f %.4f\n", p.x, p.y);
      for (const Pose2& p : m.trajectory) std::fprintf(f, "T %.4f %.4f %.6f\n", p.x, p.y, p.theta);
    }
    std::fprintf(t,
                 "# lmd ground truth v1 for %s (DESIGN.md section 4)\n"
                 "# candidates of a query: maps whose travel_start differs by more than 10 m\n"
                 "# PAIR query relevant mean_dist_m candidates   (relevant = smallest mean distance, < 0.5 m)\n"
                 "# PLACE query map...   candidates with >= 50 %% of the query's points within 0.3 m (global frame)\n",
                 d->name.c_str());
    for (const EvalQuery& q : d->queries) {
      std::fprintf(t, "PAIR %zu %zu %.5f %zu\n", q.map, q.relevant, q.mean_dist_m, q.candidates.size());
    }
    for (const EvalQuery& q : d->queries) {
      std::fprintf(t, "PLACE %zu", q.map);
      for (size_t p : q.places) std::fprintf(t, " %zu", p);
      std::fprintf(t, "\n");
    }
    const bool ok = std::fclose(f) == 0 && std::fclose(t) == 0;
    if (!ok) {
      std::fprintf(stderr, "lmd-eval export: write failed in %s\n", out.c_str());
      return 1;
    }
    std::printf("wrote %s (%zu maps) and %s (%zu queries)\n", maps_path.c_str(), d->maps.size(), truth_path.c_str(),
                d->queries.size());
  }
  return 0;
}

}  // namespace lmd::eval
