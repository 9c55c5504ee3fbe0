#include "client/cli/query_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "client/points_file.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "proto/convert.h"

namespace lmd::cli {

std::string LogName(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  for (const char* suffix : {".gz", ".log", ".mcap", ".bag", ".db3"}) {
    const std::string s = suffix;
    if (name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0) {
      name.resize(name.size() - s.size());
    }
  }
  return name;
}

Result<std::string> OneSource(const Args& args, const std::vector<std::string>& allowed, const std::string& what,
                              bool numbered) {
  static const std::vector<std::pair<std::string, std::string>> kSources = {
      {"file", "--file POINTS"}, {"log", "--log FILE"}, {"bag", "--bag PATH"}};
  std::string given, forms;
  int count = 0;
  for (const auto& [key, form] : kSources) {
    const bool is_allowed = std::find(allowed.begin(), allowed.end(), key) != allowed.end();
    if (args.Has(key)) {
      ++count;
      given = is_allowed ? key : "";
    }
    if (!is_allowed) continue;
    forms += (forms.empty() ? " as " : " or as ") + form;
    if (numbered && key != "file") forms += " --map K";
  }
  if (count != 1 || given.empty()) return Status::InvalidArgument("give " + what + forms);
  return given;
}

Result<LocalMapOptions> LocalMapOptionsFromArgs(const Args& args) {
  LocalMapOptions options;
  // Bounded: a step of 1 nm made ingest build maps for ever.
  Result<double> length = GetMetres(args, "length", options.length_m, 0.5, 100.0);
  Result<double> step = GetMetres(args, "step", options.step_m, 0.1, 100.0);
  // lmdd takes up to 0.5 rad (28.6 deg) per metre.
  Result<double> drift = GetNumber(args, "heading-drift", "degrees per metre", 0.0, 0.0, 28.0);
  if (!length.ok()) return length.status();
  if (!step.ok()) return step.status();
  if (!drift.ok()) return drift.status();
  options.length_m = *length;
  options.step_m = *step;
  options.heading_drift_rad_per_m = *drift * M_PI / 180;
  return options;
}

Result<std::vector<LocalMap>> LocalMapsFromLog(const Args& args, LocalMapOptions options) {
  const std::string path = args.Get("log");
  Result<LaserLog> log = ReadCarmenLog(path);
  if (!log.ok()) return log.status();
  options.id_prefix = LogName(path);
  std::vector<LocalMap> maps = BuildLocalMaps(*log, options);
  if (maps.empty()) return Status::InvalidArgument(path + ": the log is shorter than one local map");
  return maps;
}

Result<std::vector<LocalMap>> LocalMapsFromBag(const Args& args, LocalMapOptions options, BagLogSummary* summary) {
  std::string path = args.Get("bag");
  while (path.size() > 1 && path.back() == '/') path.pop_back();  // a directory's name, not ""
  BagLogOptions bag;
  bag.scan_topic = args.Get("scan-topic");
  bag.odom_topic = args.Get("odom-topic");
  bag.frame = args.Get("frame");
  bag.scan_matching = args.Switch("scan-matching");
  bag.allow_nan_ranges = args.Switch("allow-nan");
  bag.read.salvage_truncated = args.Switch("salvage");
  options.id_prefix = LogName(path);
  Result<LaserLog> log = ReadBagLaserLog(path, bag, summary);
  if (!log.ok()) return log.status();
  std::vector<LocalMap> maps = BuildLocalMaps(*log, options);
  if (maps.empty()) {
    const std::vector<double> travel = CumulativeTravel(*log);
    char what[160];
    std::snprintf(what, sizeof what, ": %zu posed scans over %.1f m of travel, shorter than one local map (%g m)",
                  log->scans.size(), travel.empty() ? 0.0 : travel.back(), options.length_m);
    return Status::InvalidArgument(path + what);
  }
  return maps;
}

Result<QueryInput> QueryFromArgs(const Args& args, bool* usage_error) {
  bool ignored = false;
  bool& usage = usage_error ? *usage_error : ignored;
  usage = true;
  Result<std::string> given = OneSource(args, {"file", "log", "bag"}, "the query map", /*numbered=*/true);
  if (!given.ok()) return given.status();
  Result<long> earlier = GetPositive(args, "sequence", 1, 16);
  Result<long> spacing = GetPositive(args, "sequence-step", 5, 1000);
  Result<LocalMapOptions> local_maps = LocalMapOptionsFromArgs(args);
  if (!earlier.ok()) return earlier.status();
  if (!spacing.ok()) return spacing.status();
  if (!local_maps.ok()) return local_maps.status();
  if (args.Has("file")) {
    if (args.Has("sequence")) return Status::InvalidArgument("--sequence needs --log or --bag (a points file has no route)");
    usage = false;
    Result<v1::LocalMap> map = client::ReadPointsFile(args.Get("file"));
    if (!map.ok()) return map.status();
    QueryInput input{FromProto(*map), {}};
    if (args.Has("heading-drift")) input.map.heading_drift_rad_per_m = local_maps->heading_drift_rad_per_m;
    return input;
  }
  const char* source = args.Has("bag") ? "--bag" : "--log";
  if (!args.Has("map")) return Status::InvalidArgument(std::string(source) + " needs --map K (0-based map number)");
  char* end = nullptr;
  const long k = std::strtol(args.Get("map").c_str(), &end, 10);
  if (*end != '\0' || k < 0) return Status::InvalidArgument("--map must be a map number >= 0");
  const size_t sequence = args.Has("sequence") ? static_cast<size_t>(*earlier) : 0;
  const size_t step = static_cast<size_t>(*spacing);
  if (static_cast<size_t>(k) < sequence * step) {
    return Status::InvalidArgument("--sequence " + std::to_string(sequence) + " with --sequence-step " +
                                   std::to_string(step) + " needs --map " + std::to_string(sequence * step) +
                                   " or later");
  }
  usage = false;
  Result<std::vector<LocalMap>> maps =
      args.Has("bag") ? LocalMapsFromBag(args, *local_maps, nullptr) : LocalMapsFromLog(args, *local_maps);
  if (!maps.ok()) return maps.status();
  if (static_cast<size_t>(k) >= maps->size()) {
    usage = true;
    return Status::InvalidArgument("--map " + std::to_string(k) + " is out of range: the " +
                                   std::string(args.Has("bag") ? "bag" : "log") + " gives " +
                                   std::to_string(maps->size()) + " local maps");
  }
  QueryInput input;
  input.map = std::move((*maps)[k]);
  // The route's poses stand in for the robot's odometry between its maps.
  for (size_t i = 1; i <= sequence; ++i) {
    const LocalMap& before = (*maps)[k - i * step];
    v1::SequenceMap* map = &input.sequence.emplace_back();
    *map->mutable_map() = ToProto(before);
    *map->mutable_in_query() = ToProto(Compose(Inverse(input.map.truth.global_frame), before.truth.global_frame));
    map->set_travel_m(input.map.truth.travel_start - before.truth.travel_start);
  }
  return input;
}

}  // namespace lmd::cli
