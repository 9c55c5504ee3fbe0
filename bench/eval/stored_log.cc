#include "bench/eval/stored_log.h"

#include <algorithm>
#include <cstdio>

#include "bench/eval/data_paths.h"

namespace lmd::eval {

std::unique_ptr<StoredLog> StoreLog(const Dataset& d, const LocalizeOptions& options, bool anchored) {
  auto stored = std::make_unique<StoredLog>();
  for (size_t i = 0; i < d.maps.size(); ++i) {
    stored->places.push_back(PreparePlace(d.maps[i], options));
    (void)stored->collection.Add(i, stored->places.back(), MapSource::Route{1, i + 1}, d.maps[i].trajectory);
    if (anchored) (void)stored->collection.SetAnchor(i, d.maps[i].truth.global_frame);
  }
  return stored;
}

int ForEachServedLog(Flags& args, const std::string& command, const std::function<void(const Dataset&)>& count) {
  DatasetOptions dataset_options;
  dataset_options.every_map = true;  // as lmd-eval served: every map is a query
  if (!SensorFromFlags(args, &dataset_options)) {
    std::fprintf(stderr, "lmd-eval %s: %s\n", command.c_str(), args.error().c_str());
    return 2;
  }
  std::string no_logs;
  const std::vector<std::string> logs = LogsToMeasure(args.GetAll("log"), &no_logs);
  if (logs.empty()) {
    std::fprintf(stderr, "lmd-eval %s: %s\n", command.c_str(), no_logs.c_str());
    return 2;
  }
  for (const std::string& log : logs) {
    Result<Dataset> d = LoadDataset(log, dataset_options);
    if (!d.ok()) {
      std::fprintf(stderr, "lmd-eval %s: %s\n", command.c_str(), d.status().message().c_str());
      return 1;
    }
    count(*d);
  }
  return 0;
}

bool ParseEvery(Flags& args, const std::string& command, size_t* every) {
  uint64_t n = 1;
  const bool ok = args.Count("every", 1, 1000000, 1, &n);
  if (!ok) std::fprintf(stderr, "lmd-eval %s: %s\n", command.c_str(), args.error().c_str());
  *every = static_cast<size_t>(n);
  return ok;
}

namespace {

void PrintMissRow(const MissCounts& c) {
  const double asked = static_cast<double>(std::max<size_t>(1, c.asked));
  std::printf("%-10s %6zu %8.1f %6zu %8.3f", c.name.c_str(), c.asked, static_cast<double>(c.matched) / asked, c.missed,
              1.0 - static_cast<double>(c.missed) / asked);
  for (size_t n : c.by_class) std::printf(" %15zu", n);
  std::printf("\n");
}

}  // namespace

void PrintMissTable(const std::vector<MissCounts>& logs, const std::vector<const char*>& class_names) {
  std::printf("%-10s %6s %8s %6s %8s", "log", "asked", "matched", "missed", "place@1");
  for (const char* name : class_names) std::printf(" %15s", name);
  std::printf("\n");
  MissCounts total;
  total.name = "all";
  total.by_class.assign(class_names.size(), 0);
  for (const MissCounts& c : logs) {
    PrintMissRow(c);
    total.asked += c.asked, total.missed += c.missed, total.matched += c.matched;
    for (size_t i = 0; i < c.by_class.size() && i < total.by_class.size(); ++i) total.by_class[i] += c.by_class[i];
  }
  PrintMissRow(total);
}

}  // namespace lmd::eval
