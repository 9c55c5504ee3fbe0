// lmd-eval viewpoints: how close the planned viewpoints of two local maps of
// the same place are, in the global frame, for CoG and CoR (paper Table:
// viewpoint planning). Relevant pairs come from the evaluation protocol
// (FindRelevantPairs); each map is planned in its own frame only.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/data_paths.h"
#include "core/eval/ground_truth.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "core/util/progress_bar.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd::eval {
namespace {

struct Stats {
  double median = 0, p90 = 0;
  double within_half_m = 0;  // fraction of pairs closer than 0.5 m
};

Stats Summarise(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto quantile = [&](double q) {  // linear interpolation between order statistics
    const double pos = q * static_cast<double>(v.size() - 1);
    const size_t i = static_cast<size_t>(pos);
    const double f = pos - static_cast<double>(i);
    return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
  };
  s.median = quantile(0.5), s.p90 = quantile(0.9);
  s.within_half_m = static_cast<double>(std::lower_bound(v.begin(), v.end(), 0.5) - v.begin()) / v.size();
  return s;
}

struct DatasetResult {
  std::string name;
  size_t maps = 0, pairs = 0;
  Stats cog, cor;
};

bool RunDataset(const std::string& path, const ViewpointOptions& options, DatasetResult* out) {
  out->name = DatasetName(path);
  Result<LaserLog> log = ReadCarmenLog(path);
  if (!log.ok()) {
    std::fprintf(stderr, "lmd-eval: %s\n", log.status().ToString().c_str());
    return false;
  }
  LocalMapOptions lm;
  lm.id_prefix = out->name;
  const std::vector<LocalMap> maps = BuildLocalMaps(*log, lm);
  out->maps = maps.size();
  const std::vector<RelevantPair> pairs = FindRelevantPairs(maps);
  out->pairs = pairs.size();

  std::vector<char> needed(maps.size(), 0);
  for (const RelevantPair& p : pairs) needed[p.query] = needed[p.relevant] = 1;
  const size_t n_needed = static_cast<size_t>(std::count(needed.begin(), needed.end(), 1));
  std::vector<Point2> cog(maps.size()), cor(maps.size());  // global frame
  ProgressBar bar(out->name + ": planning viewpoints", n_needed);
  for (size_t i = 0; i < maps.size(); ++i) {
    if (!needed[i]) continue;
    const ViewpointPlan plan = PlanViewpointDetailed(maps[i], options);
    cog[i] = TransformPoint(maps[i].truth.global_frame, plan.cog.origin);
    cor[i] = TransformPoint(maps[i].truth.global_frame, plan.cor.origin);
    bar.Add();
  }
  bar.Done();
  std::vector<double> d_cog, d_cor;
  for (const RelevantPair& p : pairs) {
    d_cog.push_back(std::hypot(cog[p.query].x - cog[p.relevant].x, cog[p.query].y - cog[p.relevant].y));
    d_cor.push_back(std::hypot(cor[p.query].x - cor[p.relevant].x, cor[p.query].y - cor[p.relevant].y));
  }
  out->cog = Summarise(d_cog);
  out->cor = Summarise(d_cor);
  return true;
}

std::string Json(const std::vector<DatasetResult>& results) {
  std::string s = "{\"datasets\": {";
  char buf[256];
  for (size_t i = 0; i < results.size(); ++i) {
    const DatasetResult& r = results[i];
    std::snprintf(buf, sizeof buf,
                  "%s\"%s\": {\"pairs\": %zu, \"cog\": {\"median_m\": %.4f, \"p90_m\": %.4f}, "
                  "\"cor\": {\"median_m\": %.4f, \"p90_m\": %.4f}}",
                  i ? ", " : "", r.name.c_str(), r.pairs, r.cog.median, r.cog.p90, r.cor.median, r.cor.p90);
    s += buf;
  }
  return s + "}}\n";
}

}  // namespace

int RunViewpoints(int argc, char** argv) {
  Flags args({"log", "out", "crop", "clear", "seed-stride", "min-wall", "room-min-area", "peak"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval viewpoints: %s\n", args.error().c_str());
    return 2;
  }
  const std::string out_dir = args.Get("out", "out");
  ViewpointOptions options;
  // Tuning knobs (defaults = library defaults): --crop M (GridOptions::crop_m),
  // --clear M (no_return_clear_m), --seed-stride N, --min-wall M, --room-min-area M2, --peak F.
  uint64_t seed_stride = static_cast<uint64_t>(options.room_seed_stride);
  if (!args.Number("crop", 0, 1000, options.grid.crop_m, &options.grid.crop_m) ||
      !args.Number("clear", 0, 1000, options.grid.no_return_clear_m, &options.grid.no_return_clear_m) ||
      !args.Count("seed-stride", 1, 1000, seed_stride, &seed_stride) ||
      !args.Number("min-wall", 0, 100, options.walls.min_length_m, &options.walls.min_length_m) ||
      !args.Number("room-min-area", 0, 10000, options.room_min_area_m2, &options.room_min_area_m2) ||
      !args.Number("peak", 0, 1, options.room_peak_fraction, &options.room_peak_fraction)) {
    std::fprintf(stderr, "lmd-eval viewpoints: %s\n", args.error().c_str());
    return 2;
  }
  options.room_seed_stride = static_cast<int>(seed_stride);
  // The logs are looked for once the options are checked: a mistyped option is refused first.
  std::string no_logs;
  const std::vector<std::string> logs = LogsToMeasure(args.GetAll("log"), &no_logs);
  if (logs.empty()) {
    std::fprintf(stderr, "lmd-eval viewpoints: %s\n", no_logs.c_str());
    return 2;
  }

  std::vector<DatasetResult> results;
  for (const std::string& log : logs) {
    DatasetResult r;
    if (!RunDataset(log, options, &r)) return 1;
    results.push_back(r);
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  const std::string json_path = (std::filesystem::path(out_dir) / "viewpoints.json").string();
  std::ofstream(json_path) << Json(results);

  std::printf("%-10s %6s %6s | %10s %8s %7s | %10s %8s %7s\n", "dataset", "maps", "pairs", "CoG med m", "p90 m",
              "<0.5m", "CoR med m", "p90 m", "<0.5m");
  std::vector<double> all_cog, all_cor;
  for (const DatasetResult& r : results) {
    std::printf("%-10s %6zu %6zu | %10.3f %8.3f %6.0f%% | %10.3f %8.3f %6.0f%%\n", r.name.c_str(), r.maps, r.pairs,
                r.cog.median, r.cog.p90, 100 * r.cog.within_half_m, r.cor.median, r.cor.p90, 100 * r.cor.within_half_m);
    all_cog.push_back(r.cog.median), all_cor.push_back(r.cor.median);
  }
  std::printf("%-10s %6s %6s | %10.3f %8s %7s | %10.3f %8s %7s  (median of the dataset medians)\n", "all", "", "",
              Summarise(all_cog).median, "", "", Summarise(all_cor).median, "", "");
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}

}  // namespace lmd::eval
