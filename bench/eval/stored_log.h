// What lmd-eval's miss counters (prior-misses, global-misses) share: the
// logs to read, and each log's maps stored in process as lmd-eval served
// inserts them into lmdd.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/eval_dataset.h"
#include "core/localize/memory_collection.h"

namespace lmd::eval {

struct StoredLog {
  std::vector<PreparedPlace> places;  // by map index
  MemoryCollection collection;        // map i under id i, robot 1, sequence i + 1, with its trajectory
};

// Every map of `d` stored; `anchored`: each at its log pose (a site map).
std::unique_ptr<StoredLog> StoreLog(const Dataset& d, const LocalizeOptions& options, bool anchored);

// The logs `args` names with --log (or ../shared/data's), each loaded with
// every map a query (as lmd-eval served asks them; the sensor flags as
// served's) and handed to `count` in turn. The exit code:
// 0, 2 when no log is named or found or a flag is out of range, 1 when a
// log cannot be read (one line on stderr, prefixed "lmd-eval `command`: ").
int ForEachServedLog(Flags& args, const std::string& command, const std::function<void(const Dataset&)>& count);

// --every N (default 1): every Nth query. False, with one line on stderr
// prefixed "lmd-eval `command`: ", when it is not a number of 1 or more.
bool ParseEvery(Flags& args, const std::string& command, size_t* every);

// One log's misses (or "all"), by class.
struct MissCounts {
  std::string name;
  size_t asked = 0, missed = 0;
  size_t matched = 0;             // maps scan matched, over all queries asked
  std::vector<size_t> by_class;   // as many as the command's class names
};

// The table of `logs` and their total: asked, maps matched per query,
// missed, place@1, then each class.
void PrintMissTable(const std::vector<MissCounts>& logs, const std::vector<const char*>& class_names);

}  // namespace lmd::eval
