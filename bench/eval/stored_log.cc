#include "bench/eval/stored_log.h"

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

int ForEachServedLog(const std::vector<std::string>& named, const std::string& command,
                     const std::function<void(const Dataset&)>& count) {
  std::string no_logs;
  const std::vector<std::string> logs = LogsToMeasure(named, &no_logs);
  if (logs.empty()) {
    std::fprintf(stderr, "lmd-eval %s: %s\n", command.c_str(), no_logs.c_str());
    return 2;
  }
  DatasetOptions dataset_options;
  dataset_options.every_map = true;  // as lmd-eval served: every map is a query
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

}  // namespace lmd::eval
