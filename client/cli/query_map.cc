#include "client/cli/query_map.h"

#include <cstdio>
#include <cstdlib>

#include "client/points_file.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "proto/convert.h"

namespace lmd::cli {
namespace {

std::string LogName(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  for (const char* suffix : {".gz", ".log"}) {
    const std::string s = suffix;
    if (name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0) {
      name.resize(name.size() - s.size());
    }
  }
  return name;
}

// Metres in [lo, hi] (a step of 1 nm made ingest build maps for ever).
Result<double> Metres(const Args& args, const std::string& key, double fallback, double lo, double hi) {
  if (!args.Has(key)) return fallback;
  char* end = nullptr;
  const std::string text = args.Get(key);
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(value >= lo && value <= hi)) {
    char range[64];
    std::snprintf(range, sizeof range, " must be a number of metres from %g to %g", lo, hi);
    return Status::InvalidArgument("--" + key + range + ", got '" + text + "'");
  }
  return value;
}

}  // namespace

Result<std::vector<LocalMap>> LocalMapsFromLog(const Args& args) {
  const std::string path = args.Get("log");
  Result<LaserLog> log = ReadCarmenLog(path);
  if (!log.ok()) return log.status();
  LocalMapOptions options;
  Result<double> length = Metres(args, "length", options.length_m, 0.5, 100.0);
  Result<double> step = Metres(args, "step", options.step_m, 0.1, 100.0);
  if (!length.ok()) return length.status();
  if (!step.ok()) return step.status();
  options.length_m = *length;
  options.step_m = *step;
  options.id_prefix = LogName(path);
  std::vector<LocalMap> maps = BuildLocalMaps(*log, options);
  if (maps.empty()) return Status::InvalidArgument(path + ": the log is shorter than one local map");
  return maps;
}

Result<LocalMap> QueryMapFromArgs(const Args& args) {
  if (args.Has("file") == args.Has("log")) {
    return Status::InvalidArgument("give the query map as --file POINTS or as --log FILE --map K");
  }
  if (args.Has("file")) {
    Result<v1::LocalMap> map = client::ReadPointsFile(args.Get("file"));
    if (!map.ok()) return map.status();
    return FromProto(*map);
  }
  if (!args.Has("map")) return Status::InvalidArgument("--log needs --map K (0-based map number)");
  char* end = nullptr;
  const long k = std::strtol(args.Get("map").c_str(), &end, 10);
  if (*end != '\0' || k < 0) return Status::InvalidArgument("--map must be a map number >= 0");
  Result<std::vector<LocalMap>> maps = LocalMapsFromLog(args);
  if (!maps.ok()) return maps.status();
  if (static_cast<size_t>(k) >= maps->size()) {
    return Status::InvalidArgument("--map " + std::to_string(k) + " is out of range: the log gives " +
                                   std::to_string(maps->size()) + " local maps");
  }
  return std::move((*maps)[k]);
}

}  // namespace lmd::cli
